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
The installed launch files, read as Python source (the test runs without ROS's launch tools).

A real `ros2 launch` was tried by hand (docs/ros.md); here each file must parse, start only
installed py_vision executables with the shipped parameter file, and declare the arguments the
documentation promises, typed as the parameters in config/params.yaml.
"""

import ast

import pytest
import ros_harness
import yaml

LAUNCH_DIR = ros_harness.SHARE / 'launch'
CAMERA_ARGUMENTS = {'params_file', 'video_device', 'image_width', 'image_height', 'framerate',
                    'pixel_format', 'managed', 'autostart'}
PROMISED = {
    'camera.launch.py': {'executables': {'usbcam_publisher'}, 'arguments': CAMERA_ARGUMENTS},
    'pipeline.launch.py': {'executables': {'usbcam_publisher', 'cv_bridge_test',
                                           'usbcam_subscriber'},
                           'arguments': CAMERA_ARGUMENTS | {'display', 'web_host', 'web_port',
                                                            'web_token'}},
    'two_cameras.launch.py': {'executables': {'usbcam_publisher'},
                              'arguments': CAMERA_ARGUMENTS | {'front_device', 'rear_device'}},
}


def call_name(node):
    """Return the called function's name of an ast.Call, or None."""
    func = node.func
    return func.id if isinstance(func, ast.Name) else getattr(func, 'attr', None)


def calls(tree, name):
    return [node for node in ast.walk(tree) if isinstance(node, ast.Call) and
            call_name(node) == name]


def keyword(call, name):
    return next((kw.value for kw in call.keywords if kw.arg == name), None)


def share_path(node):
    """Return the installed path of PathJoinSubstitution([FindPackageShare('py_vision'), ...])."""
    parts = node.args[0].elts
    assert call_name(parts[0]) == 'FindPackageShare'
    assert ast.literal_eval(parts[0].args[0]) == 'py_vision'
    return ros_harness.SHARE.joinpath(*(ast.literal_eval(part) for part in parts[1:]))


class LaunchFile:
    """What a launch file starts, declares and includes, read from its syntax tree."""

    def __init__(self, name):
        self.path = LAUNCH_DIR / name
        self.tree = ast.parse(self.path.read_text(), str(self.path))
        self.nodes = calls(self.tree, 'Node')
        self.lifecycle_nodes = calls(self.tree, 'LifecycleNode')
        self.includes = [share_path(call.args[0].args[0])
                         for call in calls(self.tree, 'IncludeLaunchDescription')]
        # Module-level tables of arguments: NAME = {argument: (type, description)}.
        self.tables = {
            stmt.targets[0].id: stmt.value for stmt in self.tree.body
            if isinstance(stmt, ast.Assign) and isinstance(stmt.value, ast.Dict)}

    def functions(self):
        return {stmt.name for stmt in self.tree.body if isinstance(stmt, ast.FunctionDef)}

    def declared(self):
        """Return {argument name: type name or None} of every DeclareLaunchArgument."""
        found = {}
        for call in calls(self.tree, 'DeclareLaunchArgument'):
            if isinstance(call.args[0], ast.Constant):
                found[call.args[0].value] = None
        for comprehension in ast.walk(self.tree):
            if isinstance(comprehension, ast.ListComp) and \
                    call_name(comprehension.elt) == 'DeclareLaunchArgument':
                table = self.tables[comprehension.generators[0].iter.func.value.id]
                for key, value in zip(table.keys, table.values):
                    found[key.value] = value.elts[0].id
        return found

    def all_executables(self):
        own = {ast.literal_eval(keyword(node, 'executable'))
               for node in self.nodes + self.lifecycle_nodes}
        for include in self.includes:
            own |= LaunchFile(include.name).all_executables()
        return own

    def all_arguments(self):
        arguments = set(self.declared())
        for include in self.includes:
            arguments |= LaunchFile(include.name).all_arguments()
        return arguments


def test_the_launch_files_are_installed():
    assert sorted(path.name for path in LAUNCH_DIR.iterdir()) == sorted(PROMISED)


@pytest.mark.parametrize('name', sorted(PROMISED))
def test_a_launch_file_starts_installed_nodes_with_the_shipped_parameters(name):
    launch_file = LaunchFile(name)
    assert 'generate_launch_description' in launch_file.functions()
    installed = {path.name for path in ros_harness.EXECUTABLES.iterdir()}
    for node in launch_file.nodes + launch_file.lifecycle_nodes:
        assert ast.literal_eval(keyword(node, 'package')) == 'py_vision'
        executable = ast.literal_eval(keyword(node, 'executable'))
        assert executable in installed
        # The node name stays the executable's, so that params.yaml's section applies
        # (launch_ros's LifecycleNode needs it given, and a namespace).
        if node in launch_file.lifecycle_nodes:
            assert ast.literal_eval(keyword(node, 'name')) == executable
            assert ast.literal_eval(keyword(node, 'namespace')) == ''
        else:
            assert keyword(node, 'name') is None
        first = keyword(node, 'parameters').elts[0]
        assert call_name(first) == 'LaunchConfiguration'
        assert ast.literal_eval(first.args[0]) == 'params_file'
    assert launch_file.all_executables() == PROMISED[name]['executables']
    for include in launch_file.includes:
        assert include.is_file(), '%s includes %s, which is not installed' % (name, include)
    defaults = [share_path(keyword(call, 'default_value'))
                for call in calls(launch_file.tree, 'DeclareLaunchArgument')
                if isinstance(call.args[0], ast.Constant) and call.args[0].value == 'params_file']
    assert defaults == [ros_harness.SHARE / 'config' / 'params.yaml']
    assert defaults[0].is_file()


@pytest.mark.parametrize('name', sorted(PROMISED))
def test_a_launch_file_declares_the_promised_arguments(name):
    assert LaunchFile(name).all_arguments() == PROMISED[name]['arguments']


def test_camera_arguments_reach_the_node_typed_as_its_parameters():
    # video_device:=0 must stay the string '0' (a camera index), framerate:=15 be 15.0.
    published = yaml.safe_load((ros_harness.SHARE / 'config' / 'params.yaml').read_text())[
        'usbcam_publisher']['ros__parameters']
    in_file = {name: type(value).__name__ for name, value in published.items()}
    launch_file = LaunchFile('camera.launch.py')
    typed = launch_file.declared()
    # A switch (managed) is declared with the choices true and false.
    choices = {call.args[0].value: ast.literal_eval(keyword(call, 'choices'))
               for call in calls(launch_file.tree, 'DeclareLaunchArgument')
               if isinstance(call.args[0], ast.Constant) and keyword(call, 'choices')}
    for argument, kind in typed.items():
        if argument in in_file:
            if in_file[argument] == 'bool':
                assert sorted(choices[argument]) == ['false', 'true'], argument
            else:
                assert kind == in_file[argument], argument
    assert typed['video_device'] == 'str'
    assert typed['pixel_format'] == 'str'


def test_viewer_arguments_reach_the_viewer_typed_as_its_parameters():
    # web_port:=0 must be the integer 0 (any free port), web_token:=0123... a string.
    viewer = yaml.safe_load((ros_harness.SHARE / 'config' / 'params.yaml').read_text())[
        'usbcam_subscriber']['ros__parameters']
    typed = LaunchFile('pipeline.launch.py').declared()
    in_file = {name: type(value).__name__ for name, value in viewer.items()}
    for argument in ('display', 'web_host', 'web_port', 'web_token'):
        assert typed[argument] == in_file[argument], argument
    # What the viewer is given is built from the same table, argument by argument.
    given = [node for node in ast.walk(LaunchFile('pipeline.launch.py').tree)
             if isinstance(node, ast.DictComp) and
             ast.unparse(node.generators[0].iter) == 'VIEWER_ARGUMENTS.items()']
    assert given, 'every viewer argument given reaches the viewer'


def test_the_pipeline_viewer_watches_the_processed_topic():
    launch_file = LaunchFile('pipeline.launch.py')
    viewer = [node for node in launch_file.nodes
              if ast.literal_eval(keyword(node, 'executable')) == 'usbcam_subscriber']
    assert len(viewer) == 1
    assert ast.literal_eval(keyword(viewer[0], 'remappings')) == [
        ('usb_camera/image', 'cv_bridge_image')]


def test_managed_camera_is_a_lifecycle_node_driven_to_active():
    # launch_ros is not installed here: the structure launch_ros needs is checked instead.
    launch_file = LaunchFile('camera.launch.py')
    (camera,) = launch_file.lifecycle_nodes
    assert ast.literal_eval(keyword(camera, 'executable')) == 'usbcam_publisher'
    source = ast.unparse(launch_file.tree)
    assert "given['managed'] = True" in source, 'the node must be told it is managed'
    (handler,) = calls(launch_file.tree, 'OnStateTransition')
    # Activated after configure succeeded, and not again after a deliberate deactivate.
    assert ast.literal_eval(keyword(handler, 'start_state')) == 'configuring'
    assert ast.literal_eval(keyword(handler, 'goal_state')) == 'inactive'
    assert ast.unparse(keyword(handler, 'target_lifecycle_node')) == 'camera'
    assert 'Transition.TRANSITION_ACTIVATE' in ast.unparse(keyword(handler, 'entities'))
    transitions = {ast.unparse(call.args[0]) for call in calls(launch_file.tree, 'transition')}
    assert transitions == {'Transition.TRANSITION_ACTIVATE', 'Transition.TRANSITION_CONFIGURE'}
    (change,) = calls(launch_file.tree, 'ChangeState')
    assert ast.unparse(keyword(change, 'lifecycle_node_matcher')) == 'matches_action(camera)'
    returned = [node for node in ast.walk(launch_file.tree) if isinstance(node, ast.Return)]
    assert any(ast.unparse(node.value) == '[activate_when_configured, camera, transition('
               'Transition.TRANSITION_CONFIGURE)]' for node in returned), \
        'the activating handler is registered before the configure request is emitted'


def test_two_cameras_each_by_its_device_in_a_namespace_of_its_own():
    launch_file = LaunchFile('two_cameras.launch.py')
    assert launch_file.includes == [ros_harness.SHARE / 'launch' / 'camera.launch.py']
    source = ast.unparse(launch_file.tree)
    # One group per device argument: its namespace pushed, then the camera with that device.
    (group,) = calls(launch_file.tree, 'GroupAction')
    actions = group.args[0].elts
    assert [call_name(action) for action in actions] == [
        'PushRosNamespace', 'IncludeLaunchDescription']
    assert ast.unparse(actions[0].args[0]) == "name.split('_')[0]"
    given = ast.unparse(keyword(actions[1], 'launch_arguments'))
    assert "'video_device': LaunchConfiguration(name)" in given
    assert "'params_file': LaunchConfiguration('params_file')" in given
    assert 'for name in DEVICE_ARGUMENTS' in source
    assert sorted(name.split('_')[0] for name in launch_file.declared()
                  if name.endswith('_device')) == ['front', 'rear']
