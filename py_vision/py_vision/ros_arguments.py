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
What a node's command line gives it, read before rclpy starts: its name and its parameters.

The one reader of ``--ros-args`` in py_vision. node_main uses it to make rclpy see the
parameters in the order below on every distribution; dds to size a node's shared memory before
rclpy exists; ``usbcam_publisher --list-formats`` to find the camera without a ROS graph.

Which value a parameter gets (py_vision's order, the same on Humble and Jazzy):

- Only the arguments inside ``--ros-args`` (up to ``--``) count, as rcl reads them.
- ``--params-file FILE`` and ``-p [NODE:]NAME:=VALUE`` are taken in the order they come on the
  command line, a file's sections in the order they come in the file; the last value given
  wins. So a ``-p`` after a ``--params-file`` wins over the file, and launch_ros's file of
  launch arguments (written under ``/**`` for a node it does not name) over the parameter file
  given before it.
- A file section counts when its name is the node's fully qualified name (a leading ``/`` may
  be left out) or a pattern that matches it: ``*`` stands for one name, ``**`` for any number
  (``/**``, ``/*/usbcam_publisher``), as rclpy's from Jazzy on. A ``-p`` without a node prefix
  counts for every node.

rclpy orders them its own way: Humble's 3.3.2 lets the node's own section beat any ``/**`` value
and every ``-p`` (which it stores under ``/**``), whatever their order, and ignores other
patterns; Jazzy's applies each node name in the order it first appeared, so a ``-p`` given after
a file with a ``/**`` section merges into that earlier section; and rcl, merging a value into
an earlier one of another type, keeps the earlier one. So node_main hands rclpy the command line
without its parameter arguments (`without_parameters`) and one parameter file instead, with the
node's values as read here (`parameters_file`).

Values are typed as rcl types them (not as PyYAML would): a quoted scalar is a string; ``y``,
``yes``, ``on``, ``true`` (and their ``Y``, ``Yes``, ``YES``-style spellings) are booleans,
likewise ``n``, ``no``, ``off``, ``false``; then anything C's strtol (base 0: ``0x1f``, ``017``)
reads whole is an integer, anything strtod reads whole is a double (``.inf``, ``.nan`` too);
the rest is a string. A sequence is a list of such values.

The node's name is ``-r __node:=NAME`` (or ``__name``) and ``-r __ns:=/NS`` applied to its own,
the first rule that applies winning, as in rcl. A topic's name is the node's name expanded in its
namespace, then replaced by the first ``-r [NODE:]FROM:=TO`` whose FROM, expanded the same way,
is that name (`topic_name`). (rcl refuses substitutions such as ``{node}`` in a rule.)
"""

import contextlib
from dataclasses import dataclass
import math
import os
import re
import tempfile
from typing import Any, Dict, Iterator, List, Optional, Sequence, Tuple

# rcl's flags that take the next argument as their value; any other argument stands alone.
_WITH_VALUE = ('-p', '--param', '-r', '--remap', '--params-file', '-e', '--enclave',
               '--log-level', '--log-config-file', '--log-file-name')
_TRUE = ('Y', 'y', 'yes', 'Yes', 'YES', 'true', 'True', 'TRUE', 'on', 'On', 'ON')
_FALSE = ('N', 'n', 'no', 'No', 'NO', 'false', 'False', 'FALSE', 'off', 'Off', 'OFF')
_SPECIAL_FLOATS = {'.nan': math.nan, '.NaN': math.nan, '.NAN': math.nan}
_SPECIAL_FLOATS.update({sign + inf: (-math.inf if sign == '-' else math.inf)
                        for sign in ('', '+', '-') for inf in ('.inf', '.Inf', '.INF')})
# C's strtol with base 0 and strtod, read whole (leading blanks allowed, trailing not).
_STRTOL = re.compile(r'\s*([+-]?)(?:0[xX]([0-9a-fA-F]+)|(0[0-7]*)|([1-9][0-9]*))')
_STRTOD_DECIMAL = re.compile(r'\s*[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?')
_STRTOD_HEX = re.compile(r'\s*([+-]?)(0[xX](?:[0-9a-fA-F]+\.?[0-9a-fA-F]*|\.[0-9a-fA-F]+)'
                         r'(?:[pP][+-]?[0-9]+)?)')
_STRTOD_WORD = re.compile(r'\s*([+-]?)(inf|infinity|nan(?:\([0-9A-Za-z_]*\))?)', re.IGNORECASE)
_INT64 = (-2 ** 63, 2 ** 63 - 1)
# A node-name pattern's wildcards: one name, or any number of names.
_WILDCARDS = {'/*': '(/[A-Za-z0-9_]+)', '/**': '(/[A-Za-z0-9_]+)*'}
_SMALLEST_NORMAL = 2.2250738585072014e-308
PARAMS_KEY = 'ros__parameters'
# A remapping rule's left side: [NODE:][rostopic://|rosservice://]NAME (a name has no ':').
_TOPIC_RULE = re.compile(r'(?:([^:/]+):(?!//))?(?:(rostopic|rosservice)://)?([^:]*)$')


class UnreadableArguments(ValueError):
    """A parameter file or rule cannot be read; the message says which and why (one line)."""


@dataclass(frozen=True)
class Source:
    """Parameters one argument gives: for nodes matching `pattern`, name -> value."""

    pattern: str
    values: Dict[str, Any]


def inside_ros_args(argv: Sequence[str]) -> List[str]:
    """Return the arguments inside --ros-args ... [--] sections, as rcl reads them."""
    inside = False
    found = []
    for arg in argv:
        if arg == '--ros-args':
            inside = True
        elif arg == '--':
            inside = False
        elif inside:
            found.append(arg)
    return found


def _flags(argv: Sequence[str]) -> Iterator[Tuple[str, str]]:
    """Yield (flag, value) for each flag of the ROS arguments that takes a value."""
    args = inside_ros_args(argv)
    index = 0
    while index < len(args):
        if args[index] in _WITH_VALUE and index + 1 < len(args):
            yield args[index], args[index + 1]
            index += 2
        else:
            index += 1


def node_name(argv: Sequence[str], name: str, namespace: str = '/') -> str:
    """Return the fully qualified name a node called `name` gets from argv's remapping rules."""
    new_name = new_namespace = None
    for flag, rule in _flags(argv):
        if flag not in ('-r', '--remap') or ':=' not in rule:
            continue
        match, replacement = rule.split(':=', 1)
        target, _, match = match.rpartition(':')
        if target and target != name:
            continue  # a rule for another node
        if match in ('__node', '__name') and new_name is None:
            new_name = replacement
        elif match == '__ns' and new_namespace is None:
            new_namespace = replacement
    name = new_name or name
    namespace = (new_namespace or namespace).rstrip('/')
    return '%s/%s' % (namespace, name)


def _expand(topic: str, name: str, namespace: str) -> str:
    """Return topic expanded as rcl expands it for node `name` in `namespace`."""
    if topic.startswith('/'):
        return topic
    if topic.startswith('~'):
        return '%s/%s%s' % (namespace.rstrip('/'), name, topic[1:])
    return '%s/%s' % (namespace.rstrip('/'), topic)


def topic_name(argv: Sequence[str], topic: str, fully_qualified_name: str) -> str:
    """Return the name `topic` resolves to in the node of that name, after argv's remappings."""
    namespace, _, name = fully_qualified_name.rpartition('/')
    namespace = namespace or '/'
    resolved = _expand(topic, name, namespace)
    for flag, rule in _flags(argv):
        if flag not in ('-r', '--remap') or ':=' not in rule:
            continue
        left, replacement = rule.split(':=', 1)
        found = _TOPIC_RULE.match(left)
        target, kind, match = found.groups() if found else (None, 'rosservice', '')
        if ((target and target != name) or kind == 'rosservice'
                or match in ('__node', '__name', '__ns')):
            continue
        if _expand(match, name, namespace) == resolved:
            return _expand(replacement, name, namespace)
    return resolved


def scalar(text: str, quoted: bool = False) -> Any:
    """Return a YAML scalar's value as rcl types it: bool, int, float or str (see the top)."""
    if quoted:
        return text
    if text in _TRUE:
        return True
    if text in _FALSE:
        return False
    number = _STRTOL.fullmatch(text)
    if number:
        sign, hexadecimal, octal, decimal = number.groups()
        value = int(hexadecimal, 16) if hexadecimal else int(octal, 8) if octal else int(decimal)
        value = -value if sign == '-' else value
        if _INT64[0] <= value <= _INT64[1]:
            return value
        # Out of range: strtol fails, and strtod reads it.
    if text in _SPECIAL_FLOATS:
        return _SPECIAL_FLOATS[text]
    value = _strtod(text)
    return text if value is None else value


def _strtod(text: str) -> Optional[float]:
    """Return what C's strtod reads from the whole text, or None where it fails or ERANGEs."""
    word = _STRTOD_WORD.fullmatch(text)
    if word:
        value = math.nan if word.group(2).lower().startswith('nan') else math.inf
        return -value if word.group(1) == '-' else value
    hexadecimal = _STRTOD_HEX.fullmatch(text)
    if hexadecimal:
        sign, digits = hexadecimal.groups()
        mantissa = re.split('[pP]', digits[2:])[0]
        value = float.fromhex(digits if re.search('[pP]', digits) else digits + 'p0')
    elif _STRTOD_DECIMAL.fullmatch(text):
        sign, mantissa = '', re.split('[eE]', text)[0]
        value = float(text)
    else:
        return None
    # Overflow, or a value that is not zero becoming subnormal or zero: strtod sets ERANGE.
    nonzero = re.search('[1-9a-fA-F]', mantissa) is not None
    if math.isinf(value) or (nonzero and abs(value) < _SMALLEST_NORMAL):
        return None
    return -value if sign == '-' else value


def _value(node) -> Any:
    """Return the value of a PyYAML node as rcl reads it: a scalar, or a list of one type."""
    import yaml  # only when parameters are given: PyYAML is optional on the boards
    if isinstance(node, yaml.ScalarNode):
        quoted = node.style in ('"', "'")
        if node.value == '' and not quoted:
            raise UnreadableArguments('a parameter has no value')
        return scalar(node.value, quoted)
    if isinstance(node, yaml.SequenceNode):
        values = [_value(item) for item in node.value]
        # rcl refuses a list of several types, and gives an empty one no value at all.
        if len({type(value) for value in values}) != 1:
            raise UnreadableArguments('a list of values must have one type')
        return values
    raise UnreadableArguments('expected a value or a list of values, got a mapping')


def _parameters(node, prefix: str, into: Dict[str, Any]) -> None:
    """Add the parameters under a ros__parameters mapping, nested names joined with '.'."""
    import yaml
    for key, value in node.value:
        name = prefix + key.value
        if isinstance(value, yaml.MappingNode):
            _parameters(value, name + '.', into)
        else:
            into[name] = _value(value)


def _file_sources(path: str) -> List[Source]:
    """Return the sections of a parameter file, in the file's order."""
    import yaml
    try:
        with open(path) as stream:
            root = yaml.compose(stream, Loader=yaml.SafeLoader)
    except (OSError, yaml.YAMLError) as error:
        raise UnreadableArguments('cannot read parameter file %s: %s' % (
            path, str(error).splitlines()[0] if str(error) else type(error).__name__)) from None
    sources: List[Source] = []

    def visit(node, names):
        if not isinstance(node, yaml.MappingNode):
            raise UnreadableArguments('expected node names, then %s' % PARAMS_KEY)
        for key, value in node.value:
            if key.value != PARAMS_KEY:
                visit(value, names + [key.value.strip('/')])
            elif not names or not isinstance(value, yaml.MappingNode):
                raise UnreadableArguments('%s needs node names before it and parameters in it'
                                          % PARAMS_KEY)
            else:
                values: Dict[str, Any] = {}
                _parameters(value, '', values)
                sources.append(Source('/'.join(names), values))
    if root is not None:
        try:
            visit(root, [])
        except UnreadableArguments as error:
            raise UnreadableArguments('parameter file %s: %s' % (path, error)) from None
    return sources


def _rule_source(rule: str) -> Source:
    """Return what a -p [NODE:]NAME:=VALUE rule gives."""
    import yaml
    if ':=' not in rule:
        raise UnreadableArguments('parameter rule %r has no :=' % rule)
    target, value_text = rule.split(':=', 1)
    pattern, _, name = target.rpartition(':')
    try:
        node = yaml.compose(value_text, Loader=yaml.SafeLoader)
    except yaml.YAMLError:
        raise UnreadableArguments('parameter rule %r: the value is not YAML' % rule) from None
    if node is None:
        raise UnreadableArguments('parameter rule %r has no value' % rule)
    try:
        value = _value(node)
    except UnreadableArguments as error:
        raise UnreadableArguments('parameter rule %r: %s' % (rule, error)) from None
    return Source(pattern or '/**', {name: value})


def sources(argv: Sequence[str]) -> List[Source]:
    """Return every parameter source of argv, in the order they apply (the last one wins)."""
    found: List[Source] = []
    for flag, value in _flags(argv):
        if flag in ('-p', '--param'):
            found.append(_rule_source(value))
        elif flag == '--params-file':
            found.extend(_file_sources(value))
    return found


def matches(pattern: str, fully_qualified_name: str) -> bool:
    """Return True when a node-name pattern (a file section, a -p prefix) is for that node."""
    pattern = pattern if pattern.startswith('/') else '/' + pattern
    regex = ''.join(_WILDCARDS.get(part, re.escape(part))
                    for part in re.split(r'(/\*\*|/\*)', pattern))
    return re.fullmatch(regex, fully_qualified_name) is not None


def given_parameters(argv: Sequence[str], fully_qualified_name: str) -> Dict[str, Any]:
    """
    Return every parameter argv gives the node of that name, with the value that wins.

    Raises UnreadableArguments when a parameter file or rule cannot be read.
    """
    return _given(sources(argv), fully_qualified_name)


def _given(found: List[Source], fully_qualified_name: str) -> Dict[str, Any]:
    given: Dict[str, Any] = {}
    for source in found:
        if matches(source.pattern, fully_qualified_name):
            given.update(source.values)
    return given


def yaml_text(value: Any) -> str:
    """Return value as YAML text that rcl reads back as the same type and value."""
    if isinstance(value, bool):
        return 'true' if value else 'false'
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return '.nan'
        if math.isinf(value):
            return '.inf' if value > 0 else '-.inf'
        return repr(value)
    if isinstance(value, list):
        return '[%s]' % ', '.join(yaml_text(item) for item in value)
    return "'%s'" % str(value).replace("'", "''")


def without_parameters(argv: Sequence[str]) -> List[str]:
    """Return argv without its ROS parameter arguments (-p, --param, --params-file, values)."""
    kept = []
    inside = False
    args = iter(argv)
    for arg in args:
        if arg in ('--ros-args', '--'):
            inside = arg == '--ros-args'
        elif inside and arg in _WITH_VALUE:
            # A flag and its value go together: `-r -p:=x` stays whole.
            value = next(args, None)
            if arg not in ('-p', '--param', '--params-file'):
                kept += [arg] if value is None else [arg, value]
            continue
        kept.append(arg)
    return kept


def parameters_file(given: Dict[str, Any], fully_qualified_name: str) -> str:
    """Return the text of a parameter file giving the node exactly `given` (not empty)."""
    lines = ['%s:' % fully_qualified_name, '  %s:' % PARAMS_KEY]
    lines += ["    '%s': %s" % (name.replace("'", "''"), yaml_text(value))
              for name, value in given.items()]
    return '\n'.join(lines) + '\n'


@contextlib.contextmanager
def rclpy_arguments(argv: Sequence[str], name: str) -> Iterator[List[str]]:
    """
    Yield the command line to initialise rclpy with, for the node called `name`.

    argv without its parameter arguments, and one parameter file instead, with the values read
    here (removed when the block ends; rcl has read it by then). Where argv cannot be read
    (UnreadableArguments), argv itself: rcl then says what is wrong with it.
    """
    try:
        fully_qualified_name = node_name(argv, name)
        given = given_parameters(argv, fully_qualified_name)
    except UnreadableArguments:
        yield list(argv)
        return
    args = without_parameters(argv)
    if not given:
        yield args
        return
    handle, path = tempfile.mkstemp(prefix='py_vision_%s_' % name, suffix='.yaml')
    try:
        with os.fdopen(handle, 'w') as stream:
            stream.write(parameters_file(given, fully_qualified_name))
        yield args + ['--ros-args', '--params-file', path]
    finally:
        os.unlink(path)
