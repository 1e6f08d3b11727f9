# Copyright 2026 py_vision contributors
#
# Licensed under the Apache License, Version 2.0 (the "License");
# you may not use this file except in compliance with the License.
# You may obtain a copy of the License at
#
#     http://www.apache.org/licenses/LICENSE-2.0
#
# Unless required by applicable law or agreed to in writing, software
# distributed under the License is distributed on an "AS IS" BASIS,
# WITHOUT WARRANTIES OR CONDITIONS OF ANY KIND, either express or implied.
# See the License for the specific language governing permissions and
# limitations under the License.


"""
The model files py_vision ships: where the installed (or source) copy of one is.

`colcon build` installs the package's top-level models/ folder into share/py_vision/models/;
a source checkout has it beside this package (py_vision/models/).
"""

import os
from typing import List

from py_vision.models.runtime import ModelError

__all__ = ['shipped_model', 'SHIPPED']

# The models in py_vision/models/ (README.md there says where each came from).
SHIPPED = ('palm_detection_lite.tflite', 'hand_landmark_lite.tflite',
           'face_detection_short_range.tflite')

_PACKAGE = 'py_vision'


def _folders() -> List[str]:
    """Return the folders that may hold the shipped models, most authoritative first."""
    folders = []
    try:
        from ament_index_python.packages import get_package_share_directory
        folders.append(os.path.join(get_package_share_directory(_PACKAGE), 'models'))
    except Exception:  # ament_index missing, or the workspace not sourced: look beside us
        pass
    here = os.path.dirname(os.path.abspath(__file__))
    # An install: <prefix>/lib/pythonX.Y/site-packages/py_vision/models/ -> <prefix>/share/.
    prefix = os.path.normpath(os.path.join(here, '..', '..', '..', '..', '..'))
    folders.append(os.path.join(prefix, 'share', _PACKAGE, 'models'))
    # A source tree: py_vision/py_vision/models/ -> py_vision/models/.
    folders.append(os.path.normpath(os.path.join(here, '..', '..', 'models')))
    return folders


def shipped_model(name: str) -> str:
    """Return the path of the shipped model file `name`; ModelError naming it when missing."""
    folders = _folders()
    for folder in folders:
        path = os.path.join(folder, name)
        if os.path.isfile(path):
            return path
    raise ModelError('%s: no such model shipped with py_vision (looked in %s)'
                     % (name, ', '.join(folders)))
