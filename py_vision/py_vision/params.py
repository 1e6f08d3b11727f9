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
Parameter declaration and checking shared by the nodes.

Each node declares its parameters in one place through `declare()`, which attaches a
description and accepts the types users actually type on the command line: `framerate:=30`
arrives as an integer and is taken as 30.0. A value that cannot be used raises ConfigError
naming the parameter and what it accepts.
"""

from py_vision.node_main import ConfigError
from rcl_interfaces.msg import ParameterDescriptor, SetParametersResult
from rclpy.parameter import Parameter

_KINDS = {
    float: ('a number', (int, float)),
    int: ('an integer', (int,)),
    str: ('a string', (str,)),
}


def coerce(name, value, kind, check=None, accepted=''):
    """Return value converted to kind, or raise ConfigError naming the parameter."""
    label, types = _KINDS[kind]
    if isinstance(value, bool) or not isinstance(value, types):
        raise ConfigError('parameter %s must be %s%s, got %r' % (
            name, label, ' (%s)' % accepted if accepted else '', value))
    value = kind(value)
    if check is not None and not check(value):
        raise ConfigError('parameter %s: %r is not accepted; expected %s' % (
            name, value, accepted))
    return value


class Parameters:
    """Declares a node's parameters and reads them checked and typed."""

    def __init__(self, node):
        self._node = node
        self._specs = {}
        self._declaring = False
        node.add_on_set_parameters_callback(self._on_set)

    def declare(self, name, default, description, check=None, accepted='', on_change=None):
        """
        Declare a parameter; return its checked value (ConfigError if it is unusable).

        A parameter with an on_change(value) callback can be set at run time (`ros2 param
        set`); it is checked like at start-up and the callback applies it. The others are
        read-only, and rclpy refuses to change them with a reason saying so.
        """
        kind = type(default)
        read_only = on_change is None
        self._specs[name] = (kind, check, accepted, on_change)
        descriptor = ParameterDescriptor(
            description=description, read_only=read_only, dynamic_typing=True,
            additional_constraints=accepted)
        # rclpy runs the set-callbacks for declarations too; start-up values are checked here.
        self._declaring = True
        try:
            value = self._node.declare_parameter(name, default, descriptor).value
        finally:
            self._declaring = False
        return coerce(name, value, kind, check, accepted)

    def _on_set(self, parameters):
        # Read-only parameters are refused by rclpy itself; this checks the writable ones and
        # applies them only when all of them are acceptable.
        changes = []
        for parameter in parameters if not self._declaring else ():
            spec = self._specs.get(parameter.name)
            if spec is None or spec[3] is None:
                continue
            kind, check, accepted, on_change = spec
            if parameter.type_ == Parameter.Type.NOT_SET:
                return SetParametersResult(
                    successful=False, reason='parameter %s cannot be undeclared' % parameter.name)
            try:
                changes.append((on_change, coerce(parameter.name, parameter.value, kind, check,
                                                  accepted)))
            except ConfigError as error:
                return SetParametersResult(successful=False, reason=str(error))
        for on_change, value in changes:
            on_change(value)
        return SetParametersResult(successful=True)
