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
package.xml names, as exec_depend, everything the nodes and launch files need to run.

Every module imported anywhere in the package (py_vision/ and its subpackages, launch/), also
inside functions and in try blocks (optional imports: vision_msgs), also by name through
importlib, is one of: the standard library; a ROS package (one whose share/<name>/package.xml
is in this environment's ament index, or one known to be a ROS package where it is not
installed), declared under its own name; a Python module with a rosdep key (ROSDEP_KEY),
declared under that key; or one of the optional model runtimes that rosdep has no key for
(PIP_ONLY), which load() names when none is installed.
"""

import ast
import importlib.util
import os
from pathlib import Path
import sys
import xml.etree.ElementTree as ET

PACKAGE = Path(__file__).resolve().parents[2]
# rosdep keys of the Python modules whose key is not the module's own name (rosdistro's
# rosdep/python.yaml).
ROSDEP_KEY = {'cv2': 'python3-opencv', 'numpy': 'python3-numpy', 'yaml': 'python3-yaml'}
# Optional model runtimes, imported by name where installed: rosdep has no key that installs
# them on every platform, and load() names the package to pip-install when none is there.
PIP_ONLY = {'ai_edge_litert': 'pip install ai-edge-litert',
            'tflite_runtime': 'pip install tflite-runtime',
            'onnxruntime': 'pip install onnxruntime (OpenCV DNN runs .onnx without it)'}
# ROS packages for where they are not installed (ROS 2 from PyPI has no launch, launch_ros;
# no PyPI wheel and not the boards' Humble build here has vision_msgs): by name, and message
# and interface packages by their names' ending.
ROS_PACKAGES = {'rclpy', 'launch', 'launch_ros', 'ament_index_python'}
INTERFACE_SUFFIXES = ('_msgs', '_srvs', '_interfaces')
# Functions that import the module named by their first argument.
IMPORTERS = {'import_module', '__import__', '_import'}


def exec_depends():
    root = ET.parse(PACKAGE / 'package.xml').getroot()
    return {element.text.strip() for tag in ('exec_depend', 'depend')
            for element in root.iter(tag)}


def imported_modules(path):
    """Return the top-level names of every module path imports, wherever the import is."""
    names = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            names.update(alias.name.split('.')[0] for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.level == 0:
            names.add(node.module.split('.')[0])
        elif isinstance(node, ast.Call) and node.args:
            function = node.func
            called = function.attr if isinstance(function, ast.Attribute) else getattr(
                function, 'id', '')
            first = node.args[0]
            if called in IMPORTERS and isinstance(first, ast.Constant) and isinstance(
                    first.value, str):
                names.add(first.value.split('.')[0])
    return names


def ament_prefixes(module):
    """Return the install prefixes to look in for module's package: the index's, and its own."""
    prefixes = [Path(item) for item in os.environ.get('AMENT_PREFIX_PATH', '').split(os.pathsep)
                if item]
    prefixes.append(Path(sys.prefix))
    spec = importlib.util.find_spec(module)
    if spec is not None and spec.origin:
        # <prefix>/lib/pythonX.Y/site-packages/<module>/__init__.py: every folder above it.
        prefixes.extend(Path(spec.origin).resolve().parents)
    return prefixes


def in_ament_index(name):
    """Return whether share/<name>/package.xml is installed in this environment."""
    return any((prefix / 'share' / name / 'package.xml').is_file()
               for prefix in ament_prefixes(name))


def rosdep_key(module):
    """Return module's rosdep key, '' for a module rosdep does not install, None if unknown."""
    if module in ROSDEP_KEY:
        return ROSDEP_KEY[module]
    if module in PIP_ONLY:
        return ''
    if in_ament_index(module) or module in ROS_PACKAGES or module.endswith(INTERFACE_SUFFIXES):
        return module
    return None


def run_time_sources():
    return sorted(PACKAGE.glob('py_vision/**/*.py')) + sorted(PACKAGE.glob('launch/*.py'))


def undeclared(declared):
    """Return what rosdep would not install for the package's imports, and unknown modules."""
    missing, unknown = [], []
    for path in run_time_sources():
        where = path.relative_to(PACKAGE)
        for module in sorted(imported_modules(path)):
            if module == 'py_vision' or module in sys.stdlib_module_names:
                continue
            key = rosdep_key(module)
            if key is None:
                unknown.append('%s (in %s)' % (module, where))
            elif key and key not in declared:
                missing.append('%s (import %s in %s)' % (key, module, where))
    return missing, unknown


def test_every_module_the_package_imports_is_an_exec_depend():
    missing, unknown = undeclared(exec_depends())
    assert not unknown, ('imported, but neither a ROS package here nor a module this test '
                         'knows a rosdep key for: %s; add it to ROSDEP_KEY or PIP_ONLY'
                         % ', '.join(unknown))
    assert not missing, 'rosdep would not install: %s; add <exec_depend> to package.xml' % (
        ', '.join(missing))


def test_the_check_reads_every_subpackage_and_the_ament_index():
    # The imports of the steps (geometry_msgs in hand_signs, vision_msgs tried in faces) and
    # of the model runtimes (imported by name) are seen: without them declared, both missing.
    sources = run_time_sources()
    assert {'steps', 'models', 'capture', 'viewer'} <= {path.parent.name for path in sources}
    declared = exec_depends() - {'geometry_msgs', 'vision_msgs'}
    missing, _ = undeclared(declared)
    assert any(item.startswith('geometry_msgs (import geometry_msgs in py_vision/steps/')
               for item in missing), missing
    assert any(item.startswith('vision_msgs ') for item in missing), missing
    assert {'ai_edge_litert', 'onnxruntime', 'cv2'} <= imported_modules(
        PACKAGE / 'py_vision' / 'models' / 'runtime.py')
    # ROS packages are told by the environment's ament index, not by their names alone.
    for name in ('rclpy', 'ament_index_python', 'sensor_msgs', 'geometry_msgs'):
        assert in_ament_index(name), name
    assert not in_ament_index('numpy') and rosdep_key('numpy') == 'python3-numpy'
    assert rosdep_key('requests') is None


def test_the_packaged_launch_files_can_be_run_with_ros2_launch():
    assert sorted(PACKAGE.glob('launch/*.launch.py')), 'no launch files to check'
    # `ros2 launch` is the ros2launch package; launch_ros gives the files' Node actions.
    assert {'ros2launch', 'launch', 'launch_ros'} <= exec_depends()
