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
The nodes' parameters as ROS users see them: typed, with ranges, checked, documented.

Each node lists its parameters once, as a tuple of `Spec` (class attribute ``PARAMETERS``), so
that ``--help`` can print them without starting the node. `Parameters.declare()` declares one
with its real type and a descriptor carrying the description, the range (IntegerRange or
FloatingPointRange, shown by ``ros2 param describe``) and read-only unless it can change live.

What users type on the command line is taken for what they mean: ``framerate:=15`` (an integer
to ROS) is the double 15.0 and ``video_device:=0`` the string '0'. A value that cannot be used
raises ConfigError naming the parameter and what it accepts.
"""

from dataclasses import dataclass
import math
from typing import Any, Callable, Dict, Optional, Sequence, Tuple

from py_vision.web_token import good_token, TOKEN_RULE
from rcl_interfaces.msg import (
    FloatingPointRange, IntegerRange, ParameterDescriptor, SetParametersResult)
from rclpy.parameter import Parameter


class ConfigError(Exception):
    """A parameter or a device the user gave cannot be used; the message says which and why."""


_TYPES = {bool: Parameter.Type.BOOL, int: Parameter.Type.INTEGER,
          float: Parameter.Type.DOUBLE, str: Parameter.Type.STRING}
_TYPE_WORDS = {bool: 'a boolean', int: 'an integer', float: 'a number', str: 'a string'}
_TYPE_NAMES = {bool: 'bool', int: 'integer', float: 'double', str: 'string'}
_NOT_SET_WORDS = ('null', '~', '')
# Applies changes of live parameters made together (name -> value); None, or why it refused.
Applier = Callable[[Dict[str, Any]], Optional[str]]


@dataclass(frozen=True)
class Spec:
    """
    One parameter of a node.

    `default` is its value, or a type (int, float, bool) for a parameter that is not set unless
    the user sets it (a camera control left at the camera's own value). `value_range` is
    inclusive; `choices` lists the accepted strings; `check` is any further condition, with
    `accepted` saying in words what passes it. A `live` parameter can be changed while the node
    runs (`ros2 param set`); the others are read-only. `step` is an integer range's step and
    `constraints`, when given, the descriptor's additional_constraints (a camera control says
    what it is there).
    """

    name: str
    default: Any
    description: str
    value_range: Optional[Tuple[float, float]] = None
    choices: Tuple[str, ...] = ()
    check: Optional[Callable[[Any], bool]] = None
    accepted: str = ''
    live: bool = False
    step: int = 1
    constraints: str = ''

    @property
    def kind(self) -> type:
        """Return the parameter's Python type: bool, int, float or str."""
        return self.default if isinstance(self.default, type) else type(self.default)

    @property
    def optional(self) -> bool:
        """Return True for a parameter that has no value unless the user gives one."""
        return isinstance(self.default, type)

    def accepts(self) -> str:
        """Return what the parameter accepts, in words."""
        if self.accepted:
            return self.accepted
        if self.choices:
            return ' or '.join(self.choices)
        if self.value_range is not None:
            low, high = self.value_range
            return '%s..%s' % (_number(low), _number(high))
        return _TYPE_WORDS[self.kind]

    def coerce(self, value: Any) -> Any:
        """Return value as this parameter's type, checked; raise ConfigError if unusable."""
        kind = self.kind
        if kind is float and isinstance(value, int) and not isinstance(value, bool):
            value = float(value)
        elif kind is str and isinstance(value, (int, float)) and not isinstance(value, bool):
            value = str(value)  # video_device:=0 arrives as an integer
        if type(value) is not kind:
            raise ConfigError('parameter %s must be %s (%s), got %s' % (
                self.name, _TYPE_WORDS[kind], self.accepts(), _shown(value)))
        good = True
        if kind is float and not math.isfinite(value):
            good = False
        if self.value_range is not None:
            low, high = self.value_range
            good = good and low <= value <= high
            if kind is int and self.step > 1:
                good = good and (value - low) % self.step == 0
        if self.choices and value not in self.choices:
            good = False
        if self.check is not None and good:
            good = bool(self.check(value))
        if not good:
            raise ConfigError('parameter %s: %s is not accepted; expected %s' % (
                self.name, _shown(value), self.accepts()))
        return value

    def descriptor(self) -> ParameterDescriptor:
        """
        Return the ROS descriptor: type, description, range, read-only.

        A parameter that is not set has no value to give it a type: it is declared
        dynamically typed (so that `ros2 param get` and `dump` answer "not set" instead of
        failing) and its type is checked here, in coerce(), when it is set.
        """
        descriptor = ParameterDescriptor(
            name=self.name, description=self.description, read_only=not self.live,
            dynamic_typing=self.optional)
        if not self.optional:
            descriptor.type = _TYPES[self.kind].value
        constraints = self.accepts() if (self.accepted or self.choices) else ''
        descriptor.additional_constraints = self.constraints or constraints
        if self.value_range is not None:
            low, high = self.value_range
            if self.kind is int:
                descriptor.integer_range = [IntegerRange(
                    from_value=int(low), to_value=int(high), step=self.step)]
            elif self.kind is float:
                descriptor.floating_point_range = [FloatingPointRange(
                    from_value=float(low), to_value=float(high), step=0.0)]
        return descriptor

    def help_line(self) -> str:
        """Return the parameter as one --help entry."""
        default = "not set (the camera's own value)" if self.optional else repr(self.default)
        return '  %s (%s, %s; default %s%s)\n      %s' % (
            self.name, _TYPE_NAMES[self.kind], self.accepts(), default,
            '; settable live' if self.live else '', self.description)


def _shown(value: Any) -> str:
    """Return value as an error message shows it: its repr, cut short when long."""
    text = repr(value)
    return text if len(text) <= 60 else '%s... (%d characters)' % (text[:50], len(text))


def _number(value):
    return ('%d' % value) if float(value).is_integer() else ('%g' % value)


def help_text(executable: str, specs: Sequence[Spec], summary: str) -> str:
    """Return the --help text of a node: what it does and its parameters."""
    lines = ['usage: ros2 run py_vision %s [--ros-args -p NAME:=VALUE ... '
             '| --params-file FILE | -r FROM:=TO ...]' % executable, '', summary, '',
             'parameters:']
    lines += [spec.help_line() for spec in specs]
    lines += ['  qos_overrides.<topic>.publisher.<policy> (read-only)',
              "      rclpy's QoS overrides of each topic the node publishes (e.g. "
              'qos_overrides./usb_camera/image.publisher.reliability:=best_effort): history '
              '(keep_last, keep_all), depth (1..1000), reliability (reliable, best_effort), '
              'durability (volatile, transient_local)']
    return '\n'.join(lines) + '\n'


def _good_token(token: str) -> bool:
    return token == '' or good_token(token)


def viewer_specs(display_default: str, displays: Sequence[str]) -> Tuple[Spec, ...]:
    """Return the parameters of a node that shows frames: display, web_host, web_port..."""
    return (
        Spec('display', display_default, 'where to show frames: an OpenCV window, the browser '
             'viewer, nowhere, or auto (a window where possible, else the browser viewer)',
             choices=tuple(displays)),
        Spec('web_host', '127.0.0.1', 'address the browser viewer listens on', check=bool,
             accepted='an IP address or host name'),
        Spec('web_port', 8080, 'port of the browser viewer (0: any free port)', (0, 65535)),
        Spec('web_token', '', 'the token the browser viewer requires when web_host is not a '
             'loopback address (empty: a random one at each start, logged as the URL to open)',
             check=_good_token, accepted='empty, or ' + TOKEN_RULE),
    )


class Parameters:
    """Declares a node's parameters; applies live ones when `ros2 param set` changes them."""

    def __init__(self, node):
        self._node = node
        # name -> (spec, apply(changes: name -> value) -> None or why it refused them)
        self._specs: Dict[str, Tuple[Spec, Optional[Applier]]] = {}
        self._declaring = False
        node.add_on_set_parameters_callback(self._on_set)

    @property
    def node(self):
        """Return the node whose parameters these are."""
        return self._node

    def declare(self, spec: Spec, on_change: Optional[Callable[[Any], Optional[str]]] = None
                ) -> Any:
        """
        Declare spec's parameter with its real type; return its checked value (None: not set).

        A live parameter needs on_change(value), which applies a new value once it has been
        checked like at start-up and returns None, or why it refused. Raises ConfigError when
        the start-up value is unusable.
        """
        if spec.live and on_change is None:
            raise ValueError('live parameter %s needs an on_change callback' % spec.name)
        self._specs[spec.name] = (spec, _one(spec.name, on_change) if on_change else None)
        node = self._node
        self._declaring = True
        try:
            # Read the user's value untyped first, then declare the parameter statically typed
            # with that value converted: the declared type is then the real one.
            probe = ParameterDescriptor(dynamic_typing=True)
            given = node.declare_parameter(spec.name, None, probe).value
            node.undeclare_parameter(spec.name)
            # `ros2 param dump` writes a parameter that is not set as null, which rcl reads
            # back as the string 'null': loading a dump leaves it not set.
            if spec.optional and given in _NOT_SET_WORDS:
                given = None
            if given is None:
                if spec.optional:
                    node.declare_parameter(spec.name, None, spec.descriptor(),
                                           ignore_override=True)
                    return None
                given = spec.default
            value = spec.coerce(given)
            node.declare_parameter(spec.name, value, spec.descriptor(), ignore_override=True)
        finally:
            self._declaring = False
        return value

    def declare_shown(self, spec: Spec, apply: Optional[Applier] = None) -> None:
        """
        Declare spec's parameter with spec.default, what the node found (a camera's value).

        A live one needs apply(changes): it gets the changes made together to every parameter
        declared with that same apply (name -> checked value) at once, applies them all or
        none, and returns None, or why it refused them.
        """
        if spec.live and apply is None:
            raise ValueError('live parameter %s needs an apply callback' % spec.name)
        self._specs[spec.name] = (spec, apply)
        self._declaring = True
        try:
            self._node.declare_parameter(spec.name, spec.default, spec.descriptor(),
                                         ignore_override=True)
        finally:
            self._declaring = False

    def given(self, name: str) -> Any:
        """Return the value the user gave a parameter not declared yet (None: not given)."""
        node = self._node
        self._declaring = True
        try:
            given = node.declare_parameter(
                name, None, ParameterDescriptor(dynamic_typing=True)).value
            node.undeclare_parameter(name)
        finally:
            self._declaring = False
        return None if given in _NOT_SET_WORDS else given

    def show(self, values: Dict[str, Any], specs: Sequence[Spec] = ()) -> None:
        """
        Show values the node learned elsewhere (a camera's) without applying them again.

        specs: new descriptors for parameters whose description changed (e.g. a control that
        became inactive, or a new range). Called from a timer, it never raises: what rclpy will
        not let change is left as it is. A parameter declared read-only stays read-only (rclpy
        cannot change its descriptor or its value); one whose value falls outside its new range
        takes the value in values at the same time.
        """
        node = self._node
        self._declaring = True
        try:
            for spec in specs:
                if not node.has_parameter(spec.name) or node.describe_parameter(
                        spec.name).read_only:
                    continue
                if not spec.live:
                    continue  # cannot be made read-only after declaration; the device refuses
                alternative = None
                if spec.name in values:
                    alternative = Parameter(spec.name, value=values[spec.name]
                                            ).get_parameter_value()
                try:
                    node.set_descriptor(spec.name, spec.descriptor(), alternative)
                except Exception:  # noqa: B902 - rclpy refuses: keep the old descriptor
                    continue
                self._specs[spec.name] = (spec, self._specs.get(spec.name, (None, None))[1])
            for name, value in values.items():
                if not node.has_parameter(name) or name not in self._specs:
                    continue
                if not self._specs[name][0].live or node.describe_parameter(name).read_only:
                    continue
                if node.get_parameter(name).value == value:
                    continue
                try:
                    node.set_parameters([Parameter(name, value=value)])
                except Exception:  # noqa: B902 - a value rclpy refuses stays as it was
                    continue
        finally:
            self._declaring = False

    def _on_set(self, parameters):
        # rclpy itself refuses read-only parameters, wrong types and values out of the range;
        # each applier checks the rest of its own changes and takes them all or none, and a
        # refusal puts back what the appliers before it took.
        if self._declaring:
            return SetParametersResult(successful=True)
        changes = {}
        for parameter in parameters:
            spec, apply = self._specs.get(parameter.name, (None, None))
            if spec is None or apply is None:
                continue
            if parameter.type_ == Parameter.Type.NOT_SET:
                if spec.optional:
                    return SetParametersResult(
                        successful=False, reason='parameter %s cannot be unset; restart the '
                        'node to give the camera its own value back' % parameter.name)
                return SetParametersResult(
                    successful=False, reason='parameter %s cannot be undeclared' % parameter.name)
            try:
                changes[parameter.name] = spec.coerce(parameter.value)
            except ConfigError as error:
                return SetParametersResult(successful=False, reason=str(error))
        groups: Dict[Applier, Dict[str, Any]] = {}
        for name, value in changes.items():
            groups.setdefault(self._specs[name][1], {})[name] = value
        applied = []
        for apply, group in groups.items():
            reason = apply(group)
            if reason:
                self._undo(applied)
                return SetParametersResult(successful=False, reason=reason)
            applied.append((apply, group))
        return SetParametersResult(successful=True)

    def _undo(self, applied):
        # A later group was refused: put back what the earlier ones applied.
        node = self._node
        for apply, group in reversed(applied):
            old = {name: node.get_parameter(name).value for name in group
                   if node.has_parameter(name)}
            old = {name: value for name, value in old.items() if value is not None}
            if old:
                apply(old)


def _one(name: str, on_change: Callable[[Any], Optional[str]]) -> Applier:
    """Return on_change(value) as an applier of one parameter's changes."""
    def apply(changes):
        return on_change(changes[name])
    return apply
