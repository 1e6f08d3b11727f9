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

"""package.xml names, as exec_depend, everything the nodes and launch files need to run."""

import ast
from pathlib import Path
import sys
import xml.etree.ElementTree as ET

PACKAGE = Path(__file__).resolve().parents[2]
# rosdep keys of the Python modules whose key is not the module's own name.
ROSDEP_KEY = {'cv2': 'python3-opencv', 'numpy': 'python3-numpy', 'yaml': 'python3-yaml'}
# Modules whose key is their name: ROS packages.
ROS_PACKAGES = {'rclpy', 'launch', 'launch_ros', 'ament_index_python'}


def exec_depends():
    root = ET.parse(PACKAGE / 'package.xml').getroot()
    return {element.text.strip() for tag in ('exec_depend', 'depend')
            for element in root.iter(tag)}


def imported_modules(path):
    """Return the top-level names of every module path imports, also inside functions."""
    names = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            names.update(alias.name.split('.')[0] for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.level == 0:
            names.add(node.module.split('.')[0])
    return names


def rosdep_key(module):
    if module in ROSDEP_KEY:
        return ROSDEP_KEY[module]
    if module in ROS_PACKAGES or module.endswith(('_msgs', '_srvs', '_interfaces')):
        return module
    return None


def run_time_sources():
    return sorted(PACKAGE.glob('py_vision/*.py')) + sorted(PACKAGE.glob('launch/*.py'))


def test_every_module_the_package_imports_is_an_exec_depend():
    declared = exec_depends()
    missing = []
    for path in run_time_sources():
        for module in sorted(imported_modules(path)):
            if module == 'py_vision' or module in sys.stdlib_module_names:
                continue
            key = rosdep_key(module)
            assert key, ('%s imports %s, which has no rosdep key in this test: add it to '
                         'ROSDEP_KEY' % (path.name, module))
            if key not in declared:
                missing.append('%s (import %s in %s)' % (key, module, path.name))
    assert not missing, 'rosdep would not install: %s; add <exec_depend> to package.xml' % (
        ', '.join(missing))


def test_the_packaged_launch_files_can_be_run_with_ros2_launch():
    assert sorted(PACKAGE.glob('launch/*.launch.py')), 'no launch files to check'
    # `ros2 launch` is the ros2launch package; launch_ros gives the files' Node actions.
    assert {'ros2launch', 'launch', 'launch_ros'} <= exec_depends()
