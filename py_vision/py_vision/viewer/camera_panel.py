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
The camera panel's ROS side: the controls of the node that publishes the topic a viewer shows.

`CameraPanel` finds the publisher of the shown topic in the ROS graph, reads its parameters
through the standard parameter services (list, describe, get) and keeps them current from
/parameter_events (a change made with `ros2 param set` shows at once) and a periodic re-read.
A camera control is a parameter whose descriptor's additional_constraints mark it as one
(control_descriptor); `control_json` maps each descriptor rclpy gives straight to what GET
/camera shows (range, step, menu, read-only, a button), so the panel shows what the camera
reports. What the camera is (device, pixel format, measured rate)
comes from the publisher's parameters and, when it publishes them, its /diagnostics.

When the frames come through a processing node (vision_step, cv_bridge_test), or the viewer is
that node's own, the panel also shows the parameters that node's step declares (their
descriptors marked ``step parameter of <step>``, control_descriptor), read and set the same
way: `StepParameters` follows that node.

Every ROS call is made on the executor's thread and answered there (async clients, nothing
waits): the HTTP threads hand their requests over through a guard condition and wait for the
answer with a bounded timeout. It implements camera_access.CameraAccess.
"""

import collections
import concurrent.futures
import math
import re
import threading
import time
from typing import Any, Callable, Dict, List, Optional, Tuple

from py_vision.control_descriptor import (
    is_control, parse_constraints, parse_menu, parse_step)
from py_vision.viewer.camera_access import CameraError
from rcl_interfaces.msg import (
    Parameter as ParameterMsg, ParameterEvent, ParameterType, ParameterValue)
from rcl_interfaces.srv import (
    DescribeParameters, GetParameters, ListParameters, SetParameters)
from rclpy.qos import qos_profile_parameter_events

try:
    from diagnostic_msgs.msg import DiagnosticArray
except ImportError:  # a system without diagnostic_msgs: the panel shows what it knows without
    DiagnosticArray = None

# The contract with the camera's node is control_descriptor's (docs/panel.md).
CALL_TIMEOUT_S = 3.0
REFRESH_PERIOD_S = 1.0
RELOAD_PERIOD_S = 5.0
# What the graph calls a publisher's node before that node's name has been discovered.
UNKNOWN_NODE_NAME = '_NODE_NAME_UNKNOWN_'
# A read answered short (parameters changing under it) is made again at the next refresh this
# many times in a row, then at the reload period.
SHORT_READS_RETRIED = 3
DIAGNOSTICS_STALE_S = 5.0
# The publisher's parameters that say what the camera is.
INFO_PARAMETERS = ('video_device', 'pixel_format', 'framerate', 'image_width', 'image_height')
# Live parameters of the publisher that are not camera controls but change what is shown.
STREAM_SETTINGS = ('jpeg_quality',)
# What a processing node subscribes to that leads to the camera upstream.
IMAGE_TYPES = frozenset(('sensor_msgs/msg/Image', 'sensor_msgs/msg/CompressedImage'))

_TYPE_NAMES = {ParameterType.PARAMETER_BOOL: 'bool', ParameterType.PARAMETER_INTEGER: 'integer',
               ParameterType.PARAMETER_DOUBLE: 'double', ParameterType.PARAMETER_STRING: 'string'}
_TYPE_OF_NAME = {name: kind for kind, name in _TYPE_NAMES.items()}
_BUTTON = 'button'   # a camera control's kind that is not a type: a bool that presses
_KINDS = tuple(_TYPE_OF_NAME) + (_BUTTON,)
_LEVELS = {0: 'OK', 1: 'WARN', 2: 'ERROR', 3: 'STALE'}
_STATUS = ' status'  # the diagnostics' level and message, under a key no value can have


def python_value(value: ParameterValue) -> Any:
    """Return a ParameterValue as a JSON-able Python value (None when not set)."""
    kind = value.type
    if kind == ParameterType.PARAMETER_BOOL:
        return value.bool_value
    if kind == ParameterType.PARAMETER_INTEGER:
        return value.integer_value
    if kind == ParameterType.PARAMETER_DOUBLE:
        return value.double_value
    if kind == ParameterType.PARAMETER_STRING:
        return value.string_value
    if kind == ParameterType.PARAMETER_NOT_SET:
        return None
    return '(a parameter of type %d)' % kind


def control_json(descriptor, value: ParameterValue) -> Optional[Dict[str, Any]]:
    """
    Return what GET /camera shows of one parameter of the camera's node, or None.

    The one mapping from the descriptors rclpy gives (describe_parameters) to the page: a camera
    control (its additional_constraints marked as one, control_descriptor) or a stream setting.
    Its type, range, step, read-only flag and description are the descriptor's; its menu is the
    one the description lists; `button`, `alias_of` (usb_cam's names) and `inactive` ('while
    ...') are what the constraints say. A processing step's parameter (marked as one) is mapped
    the same way, in group 'step', its choices (strings) as its menu.
    """
    words = parse_constraints(descriptor.additional_constraints, _KINDS)
    step_words = parse_step(descriptor.additional_constraints)
    if words is None and step_words is None and descriptor.name not in STREAM_SETTINGS:
        return None
    kind = _TYPE_NAMES.get(descriptor.type) or _TYPE_NAMES.get(value.type)
    if kind is None and words is not None and words.kind in _TYPE_OF_NAME:
        kind = words.kind  # not set and dynamically typed: the type is named after the mark
    bounds = step = None
    if descriptor.integer_range:
        bounds = descriptor.integer_range[0]
        step, kind = bounds.step or 1, kind or 'integer'
    elif descriptor.floating_point_range:
        bounds = descriptor.floating_point_range[0]
        step, kind = bounds.step, kind or 'double'
    read_only = bool(descriptor.read_only)
    if step_words is not None:
        menu = [{'value': choice, 'label': choice} for choice in step_words.choices] or None
        group = 'step'
    else:
        menu = parse_menu(descriptor.description)
        group = 'stream' if words is None else 'camera'
    return {'type': kind, 'value': python_value(value),
            'min': bounds.from_value if bounds else None,
            'max': bounds.to_value if bounds else None, 'step': step,
            'menu': menu, 'read_only': read_only, 'live': not read_only, 'group': group,
            'description': descriptor.description,
            'alias_of': words.alias_of if words else None,
            'inactive': words.inactive if words else None,
            'button': words is not None and words.kind == _BUTTON}


def parameter_value(name: str, control: Dict[str, Any], value: Any) -> ParameterValue:
    """Return value as control's ParameterValue; raise CameraError(400) if it is mistyped."""
    kind = control['type']
    if kind is None:  # unknown until set: the JSON type says what is meant
        kind = {bool: 'bool', int: 'integer', float: 'double', str: 'string'}.get(type(value))
    good = False
    if kind == 'bool':
        good = isinstance(value, bool)
    elif kind == 'integer':
        if isinstance(value, float) and math.isfinite(value) and value.is_integer():
            value = int(value)
        good = (isinstance(value, int) and not isinstance(value, bool) and
                -2 ** 63 <= value < 2 ** 63)
    elif kind == 'double':
        good = (isinstance(value, (int, float)) and not isinstance(value, bool) and
                math.isfinite(value))
        value = float(value) if good else value
    elif kind == 'string':
        good = isinstance(value, str)
    if not good:
        raise CameraError(400, 'control %s takes %s, got %s' % (
            name, {'bool': 'true or false', 'integer': 'an integer',
                   'double': 'a number', 'string': 'a string'}.get(kind, 'a value'),
            _json_text(value)))
    result = ParameterValue(type=_TYPE_OF_NAME[kind])
    setattr(result, {'bool': 'bool_value', 'integer': 'integer_value',
                     'double': 'double_value', 'string': 'string_value'}[kind], value)
    return result


def _json_text(value):
    text = repr(value) if not isinstance(value, (dict, list)) else type(value).__name__
    return text if len(text) <= 40 else text[:37] + '...'


class _Calls:
    """The parameter service clients of one node, and the calls on their way."""

    SERVICES = (('list', ListParameters, 'list_parameters'),
                ('describe', DescribeParameters, 'describe_parameters'),
                ('get', GetParameters, 'get_parameters'),
                ('set', SetParameters, 'set_parameters'))

    def __init__(self, node, target: str, timeout: float):
        self._node = node
        self._timeout = timeout
        self.clients = {key: node.create_client(kind, '%s/%s' % (target.rstrip('/'), name))
                        for key, kind, name in self.SERVICES}
        self._pending: List[Tuple[float, Any, Any, Any]] = []

    def ready(self, key: str) -> bool:
        return self.clients[key].service_is_ready()

    def call(self, key: str, request, on_reply: Callable[[Any], None],
             on_failure: Callable[[int, str], None]) -> None:
        """
        Send request; on_reply(response) or on_failure(status, why) follows on the executor.

        on_failure gets 504 when there is no answer within the timeout, and 503 when the
        clients are destroyed first (the node is no longer the panel's camera).
        """
        client = self.clients[key]
        future = client.call_async(request)
        entry = (time.monotonic() + self._timeout, client, future, on_failure)
        self._pending.append(entry)

        def done(finished):
            if entry in self._pending:
                self._pending.remove(entry)
                on_reply(finished.result())
        future.add_done_callback(done)

    def expire(self) -> None:
        """Give up the calls that have had no answer within the timeout."""
        now = time.monotonic()
        for entry in [e for e in self._pending if e[0] < now]:
            self._give_up(entry, 504, 'did not answer within %g s' % self._timeout)

    def destroy(self, why: str) -> None:
        """Destroy the clients; every call still waiting fails with 503 and why."""
        for entry in list(self._pending):
            self._give_up(entry, 503, why)
        for client in self.clients.values():
            self._node.destroy_client(client)

    def _give_up(self, entry, status, why):
        self._pending.remove(entry)
        entry[1].remove_pending_request(entry[2])
        entry[3](status, why)


def read_parameters(calls: _Calls, wanted: Callable[[Any], bool],
                    on_read: Callable[[List[Any], List[ParameterValue]], None],
                    failed: Callable[[int, str], None], changed: Callable[[], None],
                    current: Callable[[], bool]) -> None:
    """
    Read a node's parameters whose descriptor is wanted: list, describe, then get them.

    on_read(descriptors, values) follows on the executor; failed(status, why) when a call
    fails; changed() when a describe or get is answered short: rclpy answers with nothing at
    all when one of the names is not declared any more (the node's parameters changed under
    the read). Nothing follows once current() is False (the node is no longer the one shown).
    """
    def listed(response):
        if current():
            names = list(response.result.names)
            calls.call('describe', DescribeParameters.Request(names=names),
                       lambda reply: described(names, reply), failed)

    def described(names, response):
        if not current():
            return
        if len(response.descriptors) != len(names):
            changed()
            return
        descriptors = [d for d in response.descriptors if wanted(d)]
        calls.call('get', GetParameters.Request(names=[d.name for d in descriptors]),
                   lambda reply: got(descriptors, reply), failed)

    def got(descriptors, response):
        if not current():
            return
        if len(response.values) != len(descriptors):
            changed()
            return
        on_read(descriptors, list(response.values))

    calls.call('list', ListParameters.Request(), listed, failed)


def send_set(calls: Optional[_Calls], target: str, parameters: List[ParameterMsg],
             answer: concurrent.futures.Future) -> None:
    """Set parameters on target (its calls; None: gone): answer gets the results or why not."""
    if calls is None:
        answer.set_exception(CameraError(503, '%s is gone' % target))
    elif not calls.ready('set'):
        answer.set_exception(CameraError(503, '%s does not offer its parameter services '
                                         'now' % target))
    else:
        def replied(response):
            if len(response.results) == len(parameters):
                answer.set_result(response.results)
            else:
                answer.set_exception(CameraError(502, '%s answered %d result(s) for %d '
                                                 'parameter(s)' % (target,
                                                                   len(response.results),
                                                                   len(parameters))))
        calls.call('set', SetParameters.Request(parameters=parameters), replied,
                   lambda status, why: answer.set_exception(CameraError(
                       status, '%s %s' % (target, why))))


class StepParameters:
    """
    The parameters a processing node's step declares: read, followed and set over ROS.

    follow(node) on every refresh names the node (None: none); its parameters whose descriptor
    marks them a step's are read like the camera's controls. A node found to have none is
    remembered (`without`), so that the panel looks further up the pipeline. Its methods run on
    the executor's thread but describe(), which the HTTP threads call under the lock.
    """

    def __init__(self, node, lock: threading.Lock, timeout: float, reload_period: float,
                 clock: Callable[[], float]):
        self._node = node
        self._lock = lock
        self._timeout = timeout
        self._reload_period = reload_period
        self._clock = clock
        self.without: set = set()   # nodes known to declare no step parameters
        # Under the lock (the HTTP threads read them).
        self.target: Optional[str] = None
        self.step: Optional[str] = None
        self.parameters: Dict[str, Dict[str, Any]] = {}  # name -> control_json()
        self.loaded = False
        self.problem = ''
        self.namesakes = 1   # how many nodes in the graph bear the target's name
        # The executor's thread only.
        self.calls: Optional[_Calls] = None
        self._generation = 0
        self._loading = False
        self._last_load = -math.inf

    def describe(self) -> Optional[Dict[str, Any]]:
        """Return GET /camera's `step` (None without a processing node); under the lock."""
        if self.target is None:
            return None
        if self.namesakes > 1:
            message = _namesakes_problem(self.target, self.namesakes)
        elif self.problem:
            message = self.problem
        elif not self.loaded:
            message = 'reading the step parameters of %s' % self.target
        else:
            message = ''
        return {'node': self.target, 'step': self.step, 'message': message,
                'parameters': {name: dict(p) for name, p in self.parameters.items()}}

    def follow(self, target: Optional[str]) -> None:
        """Show target's step parameters from now on; read them when due."""
        if target != self.target:
            if self.calls is not None:
                self.calls.destroy('is no longer the processing node shown')
            self.calls = _Calls(self._node, target, self._timeout) if target else None
            self._generation += 1
            self._loading = False
            self._last_load = -math.inf
            with self._lock:
                self.target, self.step, self.parameters = target, None, {}
                self.loaded, self.problem = False, ''
        if self.calls is None:
            return
        self.calls.expire()
        if not self._loading and self._clock() - self._last_load >= self._reload_period:
            self._load()

    def reload(self) -> None:
        """Read the parameters again at the next refresh (a change may change them)."""
        self._last_load = -math.inf

    def _load(self):
        calls, generation, target = self.calls, self._generation, self.target
        if not all(calls.ready(key) for key in ('list', 'describe', 'get')):
            return
        self._loading = True
        self._last_load = self._clock()

        def current():
            return generation == self._generation

        def failed(status, why):
            if current():
                self._loading = False
                with self._lock:
                    self.problem = '%s %s' % (target, why)

        def changed():
            failed(503, 'changed its parameters while they were read; reading them again')

        def got(descriptors, values):
            parameters = {d.name: control_json(d, v) for d, v in zip(descriptors, values)}
            self._loading = False
            if not parameters:
                self.without.add(target)   # look further up the pipeline at the next refresh
            steps = [parse_step(d.additional_constraints).step for d in descriptors]
            with self._lock:
                self.parameters, self.step = parameters, steps[0] if steps else None
                self.loaded, self.problem = True, ''

        read_parameters(calls, lambda d: parse_step(d.additional_constraints) is not None,
                        got, failed, changed, current)


class CameraPanel:
    """
    The camera of the node publishing `topic`: its controls, read and set over ROS.

    runs_step: the panel's own node runs a processing step (vision_step's own viewer): its
    step's parameters are the ones shown; otherwise those of the nearest processing node the
    frames come through, if any.
    """

    def __init__(self, node, topic: str, *, call_timeout: float = CALL_TIMEOUT_S,
                 refresh_period: float = REFRESH_PERIOD_S,
                 reload_period: float = RELOAD_PERIOD_S, clock=time.monotonic,
                 runs_step: bool = False):
        self._node = node
        self._topic = topic
        self._own_name = self._full_name(node.get_namespace(), node.get_name())
        self._timeout = call_timeout
        self._reload_period = reload_period
        self._clock = clock
        self._lock = threading.Lock()  # guards what the HTTP threads read: the state below
        self._publisher: Optional[str] = None
        self._publishers: List[str] = []
        self._namesakes = 1   # how many nodes in the graph bear the camera's node's name
        self._controls: Dict[str, Dict[str, Any]] = {}  # name -> control_json()
        self._info: Dict[str, Any] = {}
        self._loaded = False
        self._problem = ''
        self._diagnostics: Optional[Tuple[float, Dict[str, str]]] = None
        # Only the executor thread uses these.
        self._calls: Optional[_Calls] = None
        self._generation = 0
        self._loading = False
        self._last_load = -math.inf
        self._short_reads = 0  # reads answered short in a row (parameters changing)
        self._without_controls = set()  # publishers known to have no camera controls
        self._via: List[str] = []
        self._runs_step = runs_step
        self._step = StepParameters(node, self._lock, call_timeout, reload_period, clock)
        self._jobs = collections.deque()
        self._wake = node.create_guard_condition(self._run_jobs)
        node.create_subscription(ParameterEvent, '/parameter_events', self._on_event,
                                 qos_profile_parameter_events)
        if DiagnosticArray is not None:
            node.create_subscription(DiagnosticArray, '/diagnostics', self._on_diagnostics, 10)
        node.create_timer(refresh_period, self._refresh)

    @staticmethod
    def _full_name(namespace, name):
        return namespace.rstrip('/') + '/' + name

    # --- what the HTTP threads call --------------------------------------------------

    def describe(self) -> Dict[str, Any]:
        """Return what the camera is and its controls (GET /camera)."""
        with self._lock:
            publisher, publishers, via = self._publisher, list(self._publishers), self._via
            step = self._step.describe()
            namesakes = self._namesakes
            controls = {name: dict(c) for name, c in self._controls.items()}
            info, loaded, problem = dict(self._info), self._loaded, self._problem
            diagnostics = self._diagnostics
        if diagnostics is not None and self._clock() - diagnostics[0] > DIAGNOSTICS_STALE_S:
            diagnostics = None
        values = diagnostics[1] if diagnostics else {}
        if publisher is None:
            message = 'no node publishes %s: start the camera (ros2 run py_vision ' \
                      'usbcam_publisher) or check the topic' % self._topic
        elif problem:
            message = problem
        elif not loaded:
            message = 'reading the controls of %s' % publisher
        elif not any(c['group'] == 'camera' for c in controls.values()):
            message = '%s has no camera controls' % publisher
        else:
            message = ''
        if via:
            message = ('the frames come through %s: this is the camera of %s. %s' % (
                ' and '.join(via), publisher, message)).strip()
        if len(publishers) > 1 and publisher is not None:
            message = ('%d nodes publish %s (%s): this is %s. %s' % (
                len(publishers), self._topic, ', '.join(publishers), publishers[0],
                message)).strip()
        if namesakes > 1 and publisher is not None:
            message = ('%s. %s' % (_namesakes_problem(publisher, namesakes), message)).strip()
        pixel_format = values.get('pixel format')
        if pixel_format is None and info.get('pixel_format') not in (None, 'auto'):
            pixel_format = '%s (requested)' % info['pixel_format']
        camera = {
            'device': info.get('video_device') or values.get('device'),
            'pixel_format': pixel_format,
            'size': values.get('size'),
            'fps': _number(values.get('frame rate')),
            'requested_fps': _number(values.get('requested rate', info.get('framerate'))),
            'status': values.get(_STATUS),
            'diagnostics': diagnostics is not None,
        }
        return {'topic': self._topic, 'publisher': publisher, 'via': via,
                'publishers': publishers, 'message': message, 'camera': camera,
                'controls': controls, 'step': step}

    def set_controls(self, values: Dict[str, Any]) -> Dict[str, Any]:
        """Set name: value on the publisher; return name: {applied, reason} (POST)."""
        with self._lock:
            publisher, loaded = self._publisher, self._loaded
            controls = dict(self._controls)
            namesakes = self._namesakes
        if publisher is None:
            raise CameraError(503, 'no node publishes %s' % self._topic)
        if namesakes > 1:
            raise CameraError(409, _namesakes_problem(publisher, namesakes))
        if not loaded:
            raise CameraError(503, 'still reading the controls of %s; try again' % publisher)
        unknown = sorted(name for name in values if name not in controls)
        if unknown:
            raise CameraError(400, 'unknown control%s %s; %s has: %s' % (
                's' if len(unknown) > 1 else '', ', '.join(map(_json_text, unknown)),
                publisher, ', '.join(controls) or 'none'))
        # An automatic mode before the controls it holds: set the other way round, a control
        # held now would be refused although the same request releases it.
        names = sorted(values, key=lambda name: not any(
            _holds(controls, name, other) for other in values if other != name))
        parameters = [
            ParameterMsg(name=name, value=parameter_value(name, controls[name], values[name]))
            for name in names]
        answer = concurrent.futures.Future()
        self._submit(lambda: self._send_set(publisher, parameters, answer))
        try:
            results = answer.result(timeout=self._timeout + 1.0)
        except concurrent.futures.TimeoutError:
            raise CameraError(504, '%s did not answer within %g s' % (
                publisher, self._timeout)) from None
        reply = {}
        with self._lock:
            for name, parameter, result in zip(names, parameters, results):
                reply[name] = {'applied': bool(result.successful), 'reason': result.reason}
                if result.successful and self._publisher == publisher and (
                        name in self._controls):
                    self._controls[name]['value'] = python_value(parameter.value)
        return reply

    def set_step_parameters(self, values: Dict[str, Any]) -> Dict[str, Any]:
        """Set name: value on the processing node's step; return name: {applied, reason}."""
        step = self._step
        with self._lock:
            target, loaded, parameters = step.target, step.loaded, dict(step.parameters)
            namesakes = step.namesakes
        if target is None:
            raise CameraError(404, 'the frames shown come through no processing node with '
                              'step parameters')
        if namesakes > 1:
            raise CameraError(409, _namesakes_problem(target, namesakes))
        if not loaded:
            raise CameraError(503, 'still reading the step parameters of %s; try again' %
                              target)
        unknown = sorted(name for name in values if name not in parameters)
        if unknown:
            raise CameraError(400, 'unknown step parameter%s %s; %s has: %s' % (
                's' if len(unknown) > 1 else '', ', '.join(map(_json_text, unknown)),
                target, ', '.join(parameters) or 'none'))
        names = list(values)
        messages = [ParameterMsg(name=name, value=parameter_value(
            name, parameters[name], values[name])) for name in names]
        answer = concurrent.futures.Future()
        self._submit(lambda: send_set(step.calls if step.target == target else None, target,
                                      messages, answer))
        try:
            results = answer.result(timeout=self._timeout + 1.0)
        except concurrent.futures.TimeoutError:
            raise CameraError(504, '%s did not answer within %g s' % (
                target, self._timeout)) from None
        reply = {}
        with self._lock:
            for name, message, result in zip(names, messages, results):
                reply[name] = {'applied': bool(result.successful), 'reason': result.reason}
                if result.successful and step.target == target and name in step.parameters:
                    step.parameters[name]['value'] = python_value(message.value)
        return reply

    def _submit(self, job):
        self._jobs.append(job)
        self._wake.trigger()

    # --- the executor thread ---------------------------------------------------------

    def _run_jobs(self):
        while self._jobs:
            self._jobs.popleft()()

    def _send_set(self, publisher, parameters, answer):
        send_set(self._calls if self._publisher == publisher else None, publisher, parameters,
                 answer)

    def _publishers_of(self, topic, *others):
        """Return the nodes publishing topic (a graph name), but this one and others."""
        if topic == self._topic:
            infos = self._node.get_publishers_info_by_topic(topic)
            # A publisher discovered before its node's name has arrived is named
            # _NODE_NAME_UNKNOWN_ for a moment: it is found at a later refresh.
            names = {self._full_name(i.node_namespace, i.node_name) for i in infos
                     if i.node_name != UNKNOWN_NODE_NAME}
        else:
            # get_publishers_info_by_topic() applies this node's remappings to the name it is
            # given (the subscriber's usb_camera/image:=cv_bridge_image would turn the name
            # up the pipeline back into the shown one): ask each node what it publishes.
            names = set()
            for name, namespace in self._node.get_node_names_and_namespaces():
                try:
                    topics = self._node.get_publisher_names_and_types_by_node(name, namespace)
                except Exception:  # the node left the graph meanwhile
                    continue
                if any(published == topic for published, _ in topics):
                    names.add(self._full_name(namespace, name))
        return sorted(names - {self._own_name, *others})

    def _upstream(self, publisher):
        """Return the node publishing the images that publisher processes (or None)."""
        namespace, _, name = publisher.rpartition('/')
        try:
            topics = self._node.get_subscriber_names_and_types_by_node(name, namespace or '/')
        except Exception:  # the node left the graph between two calls
            return None
        for topic, types in sorted(topics):
            if IMAGE_TYPES.intersection(types):
                publishers = self._publishers_of(topic, publisher)
                if publishers:
                    return publishers[0]
        return None

    def _refresh(self):
        """Follow the graph: which node's camera it is; re-read its parameters at times."""
        publishers = self._publishers_of(self._topic)
        publisher = publishers[0] if publishers else None
        # A processing node (cv_bridge_test) has no camera: the panel shows the camera of the
        # images it processes, up the pipeline.
        via, seen = [], set()
        while publisher in self._without_controls and publisher not in seen:
            seen.add(publisher)
            upstream = self._upstream(publisher)
            if upstream is None:
                break
            via.append(publisher)
            publisher = upstream
        with self._lock:
            self._via = via
        # The step shown: the viewer's own node's, or the nearest processing node's.
        candidates = ([self._own_name] if self._runs_step else []) + via
        self._step.follow(next((name for name in candidates
                                if name not in self._step.without), None))
        nodes = self._node.get_node_names_and_namespaces()
        with self._lock:
            self._step.namesakes = sum(self._full_name(namespace, name) == self._step.target
                                       for name, namespace in nodes)
        if publisher != self._publisher:
            if self._calls is not None:
                self._calls.destroy('is no longer the camera of %s' % self._topic)
            self._calls = (_Calls(self._node, publisher, self._timeout)
                           if publisher is not None else None)
            self._generation += 1
            self._loading = False
            self._last_load = -math.inf
            self._short_reads = 0
            with self._lock:
                self._publisher = publisher
                self._controls, self._info, self._loaded, self._problem = {}, {}, False, ''
                self._diagnostics = None
        namesakes = 1
        if publisher is not None:
            # Nodes that share a name share its parameter services: what the panel reads may
            # come from either, and a change reaches both.
            namesakes = sum(self._full_name(namespace, name) == publisher
                            for name, namespace in nodes)
        with self._lock:
            self._publishers = publishers
            if namesakes > 1 and self._namesakes <= 1:
                self._node.get_logger().warning('camera panel: %s' % _namesakes_problem(
                    publisher, namesakes))
            self._namesakes = namesakes
        if self._calls is None:
            return
        self._calls.expire()
        if not self._loading and self._clock() - self._last_load >= self._reload_period:
            self._load()

    def _load(self):
        """Read every parameter's name, then descriptors and values: list, describe, get."""
        calls, generation = self._calls, self._generation
        if not all(calls.ready(key) for key in ('list', 'describe', 'get')):
            return  # its services are not discovered yet: the next refresh tries again
        self._loading = True
        self._last_load = self._clock()

        def current():
            return generation == self._generation

        def failed(status, why):
            if current():
                self._loading = False
                with self._lock:
                    self._problem = '%s %s' % (self._publisher, why)

        def changed():
            # That says nothing about its controls: read them all again at the next refresh.
            failed(503, 'changed its parameters while they were read; reading them again')
            self._short_reads += 1
            if self._short_reads < SHORT_READS_RETRIED:
                self._last_load = -math.inf   # at the next refresh; then at the reload period

        def wanted(descriptor):
            return (descriptor.name in INFO_PARAMETERS or
                    is_control(descriptor.additional_constraints) or
                    descriptor.name in STREAM_SETTINGS)

        def got(descriptors, values):
            controls, info = {}, {}
            for descriptor, value in zip(descriptors, values):
                control = control_json(descriptor, value)
                if control is not None:
                    controls[descriptor.name] = control
                if descriptor.name in INFO_PARAMETERS:
                    info[descriptor.name] = python_value(value)
            self._short_reads = 0
            # Camera controls first, then the stream settings, each in the node's order.
            ordered = dict(sorted(controls.items(),
                                  key=lambda item: item[1]['group'] != 'camera'))
            self._loading = False
            if not any(c['group'] == 'camera' for c in controls.values()):
                self._without_controls.add(self._publisher)
                self._last_load = -math.inf  # look up the pipeline at the next refresh
            with self._lock:
                self._controls, self._info = ordered, info
                self._loaded, self._problem = True, ''

        read_parameters(calls, wanted, got, failed, changed, current)

    def _on_event(self, event):
        """Apply a parameter change of the publisher or the step (made here or elsewhere)."""
        if event.node == self._step.target:
            self._on_step_event(event)
        if event.node != self._publisher:
            return
        reload = False
        with self._lock:
            for parameter in list(event.new_parameters) + list(event.changed_parameters):
                control = self._controls.get(parameter.name)
                if control is not None:
                    control['value'] = python_value(parameter.value)
                    if control['type'] is None:
                        control['type'] = _TYPE_NAMES.get(parameter.value.type)
                elif parameter.name in INFO_PARAMETERS:
                    self._info[parameter.name] = python_value(parameter.value)
                else:
                    reload = True  # a new parameter: it may be a control (a new camera)
            # Any change may change what else is active (automatic exposure on: the exposure
            # time is inactive), which only the descriptors say: re-read them at the next tick.
            reload = reload or bool(event.changed_parameters) or bool(event.deleted_parameters)
        if reload:
            self._last_load = -math.inf

    def _on_step_event(self, event):
        step = self._step
        with self._lock:
            for parameter in list(event.new_parameters) + list(event.changed_parameters):
                shown = step.parameters.get(parameter.name)
                if shown is not None:
                    shown['value'] = python_value(parameter.value)
                    if shown['type'] is None:
                        shown['type'] = _TYPE_NAMES.get(parameter.value.type)
        if event.new_parameters or event.deleted_parameters:
            step.reload()

    def _on_diagnostics(self, message):
        if self._publisher is None:
            return
        names = (self._publisher, self._publisher.lstrip('/'), self._publisher.split('/')[-1])
        for status in message.status:
            owner = status.name.split(':', 1)[0].strip()
            if owner in names and any(item.key == 'pixel format' for item in status.values):
                values = {item.key: item.value for item in status.values}
                values.setdefault('device', status.hardware_id)
                level = status.level[0] if isinstance(status.level, bytes) else status.level
                values[_STATUS] = '%s: %s' % (_LEVELS.get(level, level), status.message)
                with self._lock:
                    self._diagnostics = (self._clock(), values)


def _namesakes_problem(publisher: str, count: int) -> str:
    return ('%d nodes are named %s: the panel cannot tell them apart and a change would reach '
            'all of them; give each its own name (--ros-args -r __node:=<name>)' % (
                count, publisher))


def _holds(controls: Dict[str, Dict[str, Any]], owner: str, name: str) -> bool:
    """Return True when control `name` is inactive now because of control `owner`."""
    def real(control_name):
        control = controls.get(control_name)
        return (control.get('alias_of') or control_name) if control else control_name
    held = controls.get(real(name))
    return bool(held and held.get('inactive') and re.match(
        r'while %s\b' % re.escape(real(owner)), held['inactive']))


def _number(text):
    """Return a number given as a string or number ('15.0 fps' -> 15.0), or None."""
    if isinstance(text, (int, float)) and not isinstance(text, bool):
        return float(text)
    if not isinstance(text, str):
        return None
    try:
        return float(text.split()[0])
    except (ValueError, IndexError):
        return None
