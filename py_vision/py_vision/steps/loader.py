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
The one place that turns a step's name (the `step` parameter) into a step.

A built-in step by its short name (BUILT_IN), or the user's own as `module.path:Class`,
imported from PYTHONPATH or the user's sourced package. Whatever goes wrong (no such module or
class, not a step, its constructor or start() fails, a model missing or unreadable, a runtime
not installed) is a StepError: a ConfigError, so the node ends at start with status 1 and this
one line naming the step, no traceback.
"""

import importlib
from typing import Dict, Optional, Sequence, Tuple

from py_vision.params import ConfigError, Spec
from py_vision.steps.api import ProcessesFrames, step_parameters, StepContext

__all__ = ['BUILT_IN', 'find', 'make', 'start', 'StepError']

BUILT_IN: Dict[str, str] = {
    'circle': 'py_vision.steps.circle:Circle',
    'hand_signs': 'py_vision.steps.hand_signs:HandSigns',
    'faces': 'py_vision.steps.faces:Faces',
}


class StepError(ConfigError):
    """A step that cannot be found, made or started; the message is one line naming it."""


def _one_line(error: BaseException) -> str:
    text = ' '.join(str(error).split())
    return '%s: %s' % (type(error).__name__, text) if text else type(error).__name__


def _is_error_of(error: ImportError, module: str) -> bool:
    # "No module named 'a.b'" about the step's own module (or a parent), not an import inside it.
    missing = getattr(error, 'name', None) or ''
    return bool(missing) and (module == missing or module.startswith(missing + '.'))


def find(name: str) -> Tuple[str, type]:
    """Return (module.path:Class, the class) for a step's name; raise StepError if unusable."""
    target = BUILT_IN.get(name, name)
    module_name, colon, class_name = target.partition(':')
    if not colon or not module_name or not class_name:
        raise StepError(
            'step %r: not a built-in step (%s) nor module.path:Class' % (
                name, ', '.join(BUILT_IN)))
    try:
        module = importlib.import_module(module_name)
    except ImportError as error:
        if _is_error_of(error, module_name):
            raise StepError('step %r: no module %s on PYTHONPATH (is its package sourced?)'
                            % (name, module_name)) from None
        raise StepError('step %r: importing module %s failed: %s' % (
            name, module_name, _one_line(error))) from None
    except Exception as error:  # noqa: B902 - whatever the user's module raises on import
        raise StepError('step %r: importing module %s failed: %s' % (
            name, module_name, _one_line(error))) from None
    step_class = getattr(module, class_name, None)
    if step_class is None:
        raise StepError('step %r: module %s has no %s' % (name, module_name, class_name))
    if not isinstance(step_class, type) or not callable(getattr(step_class, 'process', None)):
        raise StepError('step %r: %s is not a step (a class with a process(image, header) '
                        'method)' % (name, target))
    specs = step_parameters(step_class)
    if not all(isinstance(spec, Spec) for spec in specs):
        raise StepError('step %r: %s.PARAMETERS must hold py_vision.params.Spec entries' % (
            name, target))
    return target, step_class


def check_parameters(name: str, specs: Sequence[Spec], node_specs: Sequence[Spec]) -> None:
    """Raise StepError when a step's parameter has the name of one of the node's own."""
    taken = {spec.name for spec in node_specs}
    clash = sorted(spec.name for spec in specs if spec.name in taken)
    if clash:
        raise StepError("step %r: its parameter(s) %s clash with the node's own" % (
            name, ', '.join(clash)))


def make(name: str, step_class: type) -> ProcessesFrames:
    """Return step_class(); raise StepError naming the step when its constructor fails."""
    try:
        return step_class()
    except Exception as error:  # noqa: B902 - whatever the user's constructor raises
        raise StepError('step %r: creating %s failed: %s' % (
            name, step_class.__name__, _one_line(error))) from None


def start(name: str, step: ProcessesFrames, context: StepContext) -> Optional[str]:
    """Start the step (its optional hook); return its note; raise StepError if it fails."""
    begin = getattr(step, 'start', None)
    if begin is None:
        return None
    try:
        note = begin(context)
    except Exception as error:  # noqa: B902 - a model missing or unreadable, a runtime absent
        raise StepError('step %r: starting it failed: %s' % (name, _one_line(error))) from None
    return None if note is None else str(note)
