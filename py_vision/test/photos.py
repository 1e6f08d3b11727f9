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
Real photographs for the model tests: the pictures scikit-image ships, read by path.

scikit-image's wheel carries a few photographs in skimage/data/ (astronaut.png is NASA's
portrait of Eileen Collins, public domain). They are read with OpenCV from the installed
package's folder, without importing skimage (whose import differs between its versions).
"""

import importlib.util
import os

import cv2
import numpy as np


def photo(name: str) -> np.ndarray:
    """Return the photograph skimage/data/<name> as a bgr8 image."""
    spec = importlib.util.find_spec('skimage')
    assert spec is not None, 'scikit-image is not installed (requirements-test.txt)'
    path = os.path.join(spec.submodule_search_locations[0], 'data', name)
    image = cv2.imread(path, cv2.IMREAD_COLOR)
    assert image is not None, 'cannot read %s' % path
    return image
