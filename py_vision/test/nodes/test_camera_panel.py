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
The camera panel's API end to end: a real usbcam_publisher and the viewer of a subscriber.

What GET /camera shows is checked against what the publisher itself says through its
parameter services (the expected ranges come from its descriptors, never from this file), and
what POST /camera/controls does is checked there too. The same for a processing node's step
parameters (GET /camera's `step`, POST /camera/step), with a user's own step.
"""

import http.client
import json
import os
import re

from fake_clock import FakeClock
from param_client import describe_parameters, get_parameters, set_parameter
from rcl_interfaces.srv import ListParameters
from ros_harness import wait_until

URL_LINE = r'viewer at http://[^\s/]+:(\d+)/(\?token=([\w.~-]+))?'
CONTROL_MARK = 'camera control'
PUBLISHER = 'usbcam_publisher'


def call(port, method, path, body=None, headers=None, timeout=10.0):
    """Send one request to 127.0.0.1:port; return (status, headers, body as JSON or bytes)."""
    connection = http.client.HTTPConnection('127.0.0.1', port, timeout=timeout)
    try:
        connection.request(method, path, body=body, headers=headers or {})
        response = connection.getresponse()
        data = response.read()
        answer = data
        if response.getheader('Content-Type', '').startswith('application/json'):
            answer = json.loads(data)
        return response.status, {k.lower(): v for k, v in response.getheaders()}, answer
    finally:
        connection.close()


def post(port, values, headers=None, path='/camera/controls'):
    body = values if isinstance(values, bytes) else json.dumps(values).encode()
    return call(port, 'POST', path, body,
                dict({'Content-Type': 'application/json'}, **(headers or {})))


def camera(port):
    status, _, state = call(port, 'GET', '/camera')
    assert status == 200, state
    return state


def start_viewer(launch, **params):
    subscriber = launch('usbcam_subscriber', params=dict(
        {'display': 'web', 'web_port': 0}, **params))
    match = subscriber.wait_for_output(URL_LINE)
    return subscriber, int(match.group(1)), match.group(3)


def camera_controls(peer):
    """Return name: descriptor of the publisher's camera controls, as it describes them."""
    from param_client import _call
    names = _call(peer, PUBLISHER, ListParameters, 'list_parameters',
                  ListParameters.Request()).result.names
    return {d.name: d for d in describe_parameters(peer, PUBLISHER, names)
            if d.additional_constraints.startswith(CONTROL_MARK)}


def value_of(parameter_value):
    return {1: parameter_value.bool_value, 2: parameter_value.integer_value,
            3: parameter_value.double_value, 4: parameter_value.string_value}.get(
                parameter_value.type)


def test_the_api_shows_and_sets_the_publishers_controls(launch, peer):
    launch('usbcam_publisher', params={'video_device': 'synthetic', 'framerate': 15.0})
    subscriber, port, token = start_viewer(launch)
    assert token is None, 'a loopback viewer needs no token'

    state = wait_until(lambda: (lambda s: s if s['controls'] else None)(camera(port)), 30,
                       interval=0.2, what='the controls in GET /camera')
    assert state['publisher'] == '/' + PUBLISHER
    assert state['topic'] == '/usb_camera/image'
    assert state['camera']['device'] == 'synthetic'
    assert state['step'] is None, 'no processing node between the camera and the viewer'
    wait_until(lambda: camera(port)['shown'].get('size') == '640x480', 15, interval=0.2,
               what='the size of the frames shown')

    # Every camera control the publisher describes, with its range, and nothing else of it
    # but the stream settings.
    # (A describe answered short fails here, naming who serves it: param_client.)
    descriptors = camera_controls(peer)
    assert descriptors, 'the publisher marks no parameter as a camera control'
    shown = state['controls']
    assert {n for n, c in shown.items() if c['group'] == 'camera'} == set(descriptors)
    assert shown['jpeg_quality']['group'] == 'stream'
    for name, descriptor in descriptors.items():
        control = shown[name]
        assert control['read_only'] == descriptor.read_only, name
        if descriptor.integer_range:
            bounds = descriptor.integer_range[0]
            assert (control['min'], control['max'], control['step']) == (
                bounds.from_value, bounds.to_value, bounds.step or 1), name
            assert control['type'] == 'integer', name
    values = get_parameters(peer, PUBLISHER, list(descriptors))
    assert {n: shown[n]['value'] for n in descriptors} == {
        n: value_of(v) for n, v in zip(descriptors, values)}

    # A change in the panel is the publisher's parameter.
    bounds = descriptors['brightness'].integer_range[0]
    step = bounds.step or 1
    target = (bounds.from_value + bounds.to_value) // 2 + 10 * step
    status, _, answer = post(port, {'brightness': target})
    assert status == 200, answer
    assert answer['results']['brightness'] == {'applied': True, 'reason': ''}
    assert value_of(get_parameters(peer, PUBLISHER, ['brightness'])[0]) == target
    assert camera(port)['controls']['brightness']['value'] == target

    # A value the node refuses: the answer is the node's own reason, and nothing changed.
    too_high = bounds.to_value + step
    status, _, answer = post(port, {'brightness': too_high})
    assert status == 200, answer
    result = answer['results']['brightness']
    assert result['applied'] is False
    assert result['reason'] == set_parameter(peer, PUBLISHER, 'brightness', too_high).reason
    assert result['reason']
    assert value_of(get_parameters(peer, PUBLISHER, ['brightness'])[0]) == target

    # A change made elsewhere (ros2 param set) shows up.
    contrast = descriptors['contrast'].integer_range[0]
    wanted = contrast.from_value + (contrast.step or 1)
    assert set_parameter(peer, PUBLISHER, 'contrast', wanted).successful
    wait_until(lambda: camera(port)['controls']['contrast']['value'] == wanted, 10,
               interval=0.1, what='the contrast set elsewhere in GET /camera')

    # Several at once: each has its own answer.
    status, _, answer = post(port, {'brightness': target - step, 'contrast': too_high * 1000})
    assert status == 200
    assert answer['results']['brightness']['applied'] is True
    assert answer['results']['contrast']['applied'] is False
    assert 'Traceback' not in subscriber.output()


def test_bad_requests_are_4xx_with_the_reason_and_the_node_stays_up(launch):
    launch('usbcam_publisher', params={'video_device': 'synthetic', 'framerate': 15.0})
    subscriber, port, _ = start_viewer(launch)
    wait_until(lambda: camera(port)['controls'], 30, interval=0.2, what='the controls')

    cases = [
        (b'{brightness: 1', 'application/json', 400, 'not JSON'),
        (b'[1, 2]', 'application/json', 400, 'JSON object'),
        (b'{}', 'application/json', 400, 'JSON object'),
        (b'{"no_such_control": 1}', 'application/json', 400, 'unknown control'),
        (b'{"brightness": "bright"}', 'application/json', 400, 'an integer'),
        (b'{"brightness": true}', 'application/json', 400, 'an integer'),
        (b'{"brightness": 1.5}', 'application/json', 400, 'an integer'),
        (b'{"brightness": 123456789012345678901234567890}', 'application/json', 400,
         'an integer'),
        (b'{"brightness": NaN}', 'application/json', 400, 'an integer'),
        (b'{"brightness": 1}', 'text/plain', 415, 'application/json'),
        (b'{"brightness": 1}', 'application/x-www-form-urlencoded', 415, 'application/json'),
        (b'{"x": "%s"}' % (b'a' * 100000), 'application/json', 413, 'at most'),
        (b'\xff\xfe{}', 'application/json', 400, 'not JSON'),
    ]
    for body, content_type, expected, words in cases:
        status, _, answer = call(port, 'POST', '/camera/controls', body,
                                 {'Content-Type': content_type})
        assert status == expected, (body[:40], status, answer)
        assert words in answer['error'], (body[:40], answer)
    status, _, answer = call(port, 'POST', '/camera', b'{}',
                             {'Content-Type': 'application/json'})
    assert status == 405
    # A page of another site cannot change anything (its Origin is not the viewer's).
    status, _, answer = post(port, {'brightness': 1}, {'Origin': 'http://evil.example'})
    assert status == 403 and 'Origin' in answer['error']
    # Nor read anything through a name rebound to 127.0.0.1.
    status, _, answer = call(port, 'GET', '/camera', headers={'Host': 'evil.example:%d' % port})
    assert status == 403
    # Still serving, no traceback.
    assert call(port, 'GET', '/stats')[0] == 200
    assert post(port, {'brightness': 0})[2]['results']['brightness']['applied'] is True
    assert subscriber.proc.poll() is None
    assert 'Traceback' not in subscriber.output()


def test_without_a_publisher_the_panel_says_so(launch):
    subscriber, port, _ = start_viewer(launch)
    state = camera(port)
    assert state['publisher'] is None and state['controls'] == {}
    assert 'no node publishes /usb_camera/image' in state['message']
    status, _, answer = post(port, {'brightness': 1})
    assert status == 503 and 'no node publishes' in answer['error']


def test_off_loopback_every_request_needs_the_token(launch):
    # Bound to every interface (reached here through 127.0.0.1): loopback is judged by the
    # address the viewer is bound to, not by where a request comes from.
    subscriber, port, token = start_viewer(launch, web_host='0.0.0.0')
    assert token, 'no token in the logged URL of a viewer on 0.0.0.0'
    log = subscriber.output()
    assert log.count(token) == 1, 'the token is written more than once'

    for path in ('/', '/stream', '/snapshot.jpg', '/stats', '/camera'):
        status, headers, _ = call(port, 'GET', path)
        assert status == 401, path
    assert call(port, 'GET', '/stats', headers={'Authorization': 'Bearer wrong'})[0] == 401
    assert call(port, 'GET', '/?token=wrong')[0] == 401
    assert post(port, {'brightness': 1})[0] == 401

    # Opening the logged URL sets the cookie and leads to the clean URL.
    status, headers, _ = call(port, 'GET', '/?token=' + token)
    assert status == 303 and headers['location'] == '/'
    cookie = headers['set-cookie']
    assert 'HttpOnly' in cookie and 'SameSite=Strict' in cookie
    name_value = cookie.split(';')[0]
    assert name_value.endswith('=' + token)
    assert call(port, 'GET', '/', headers={'Cookie': name_value})[0] == 200
    assert call(port, 'GET', '/camera', headers={'Cookie': name_value})[0] == 200
    assert call(port, 'GET', '/stats',
                headers={'Authorization': 'Bearer ' + token})[0] == 200

    # A change with the cookie needs the page's own Origin; a script's header needs none.
    own = {'Cookie': name_value, 'Origin': 'http://127.0.0.1:%d' % port}
    assert post(port, {'brightness': 1}, {'Cookie': name_value})[0] == 403
    assert post(port, {'brightness': 1}, dict(own, Origin='http://evil.example'))[0] == 403
    assert post(port, {'brightness': 1}, own)[0] == 503  # past the checks: no publisher
    assert post(port, {'brightness': 1}, {'Authorization': 'Bearer ' + token})[0] == 503
    assert subscriber.output().count(token) == 1
    assert 'Traceback' not in subscriber.output()


def test_web_token_sets_the_token(launch):
    chosen = 'a-token-of-my-own-1234'
    subscriber, port, token = start_viewer(launch, web_host='0.0.0.0', web_token=chosen)
    assert token == chosen
    assert call(port, 'GET', '/stats', headers={'Authorization': 'Bearer ' + chosen})[0] == 200
    bad = launch('usbcam_subscriber', params={'display': 'web', 'web_port': 0,
                                              'web_token': 'short'}, name='bad_token')
    assert bad.wait_exit(20) == 1
    assert re.search(r'web_token.*at least 16', bad.output())
    assert 'Traceback' not in bad.output()


# What a control looks like to the panel, from descriptors written as the contract says
# (no ROS graph: the descriptors are made here).

def ros_value(value):
    from param_client import parameter_value
    return parameter_value(value)


def descriptor(name, **fields):
    from rcl_interfaces.msg import ParameterDescriptor
    return ParameterDescriptor(name=name, **fields)


def test_controls_are_read_from_descriptors_as_the_contract_writes_them():
    from py_vision.viewer.camera_panel import control_json, parse_menu
    from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterValue

    exposure = control_json(descriptor(
        'auto_exposure', type=2, description='Auto Exposure; menu: 1=Manual Mode; '
        '3=Aperture Priority Mode', additional_constraints='camera control, menu',
        integer_range=[IntegerRange(from_value=0, to_value=3, step=1)]), ros_value(3))
    assert exposure == {
        'type': 'integer', 'value': 3, 'min': 0, 'max': 3, 'step': 1, 'read_only': False,
        'live': True, 'group': 'camera', 'description': exposure['description'],
        'menu': [{'value': 1, 'label': 'Manual Mode'},
                 {'value': 3, 'label': 'Aperture Priority Mode'}],
        'alias_of': None, 'inactive': None, 'button': False}

    temperature = control_json(descriptor(
        'white_balance_temperature', type=2, additional_constraints='camera control',
        integer_range=[IntegerRange(from_value=2800, to_value=6500, step=10)]),
        ros_value(4600))
    assert (temperature['min'], temperature['max'], temperature['step']) == (2800, 6500, 10)
    assert temperature['menu'] is None and temperature['inactive'] is None

    # Optional words after the mark: why a control is inactive, and another name of one.
    held = control_json(descriptor(
        'gain', type=2, additional_constraints='camera control 0x00980913 '
        '(integer, step 1, default 100); inactive while gain_automatic is 1',
        integer_range=[IntegerRange(from_value=0, to_value=255, step=1)]), ros_value(100))
    assert held['inactive'] == 'while gain_automatic is 1'
    alias = control_json(descriptor(
        'exposure', type=2, additional_constraints='camera control: usb_cam name for '
        'exposure_time_absolute'), ros_value(156))
    assert alias['alias_of'] == 'exposure_time_absolute' and alias['inactive'] is None

    fixed = control_json(descriptor(
        'exposure_time_absolute', type=2, read_only=True,
        additional_constraints='camera control'), ros_value(156))
    assert fixed['read_only'] and fixed['live'] is False

    switch = control_json(descriptor(
        'focus_automatic_continuous', type=1, additional_constraints='camera control'),
        ros_value(True))
    assert (switch['type'], switch['value'], switch['min'], switch['button']) == (
        'bool', True, None, False)
    # A button is a bool the page shows as a button to press.
    button = control_json(descriptor(
        'do_white_balance', type=1, additional_constraints='camera control 0x0098090d '
        '(button)'), ros_value(False))
    assert (button['type'], button['value'], button['button']) == ('bool', False, True)
    # A 64-bit control's whole range.
    wide = control_json(descriptor(
        'integer_64_bits', type=2, additional_constraints='camera control 0x0098f903 '
        '(integer64, step 1, default 0)',
        integer_range=[IntegerRange(from_value=-2 ** 63, to_value=2 ** 63 - 1, step=1)]),
        ros_value(2 ** 40))
    assert (wide['type'], wide['min'], wide['max'], wide['value']) == (
        'integer', -2 ** 63, 2 ** 63 - 1, 2 ** 40)

    # Not set yet (usb_cam's names): dynamically typed, the type named after the mark.
    unset = control_json(descriptor(
        'autofocus', dynamic_typing=True, additional_constraints='camera control, bool'),
        ParameterValue())
    assert unset['type'] == 'bool' and unset['value'] is None
    gain = control_json(descriptor(
        'gain', dynamic_typing=True, additional_constraints='camera control, integer',
        floating_point_range=[]), ParameterValue())
    assert gain['type'] == 'integer'
    zoom = control_json(descriptor(
        'zoom', type=3, additional_constraints='camera control',
        floating_point_range=[FloatingPointRange(from_value=1.0, to_value=4.0)]),
        ros_value(1.0))
    assert zoom['type'] == 'double' and (zoom['min'], zoom['max']) == (1.0, 4.0)

    assert control_json(descriptor(
        'framerate', type=3, additional_constraints='a number > 0'), ros_value(10.0)) is None
    assert control_json(descriptor('jpeg_quality', type=2), ros_value(80))['group'] == 'stream'
    assert parse_menu('no menu here') is None
    assert parse_menu('Power Line Frequency; menu: 0=Disabled; 1=50 Hz; 2=60 Hz') == [
        {'value': 0, 'label': 'Disabled'}, {'value': 1, 'label': '50 Hz'},
        {'value': 2, 'label': '60 Hz'}]


def test_a_step_parameter_is_read_from_its_descriptor_as_vision_step_marks_it():
    # What vision_step declares for a step's Spec (marked) maps to a typed panel entry.
    from py_vision.params import Spec
    from py_vision.viewer.camera_panel import control_json
    from py_vision.vision_step import marked

    gain = marked(Spec('gain', 1.0, 'how bright', (0.0, 4.0), live=True), 'mine:Step')
    shown = control_json(gain.descriptor(), ros_value(1.5))
    assert shown == {
        'type': 'double', 'value': 1.5, 'min': 0.0, 'max': 4.0, 'step': 0.0, 'menu': None,
        'read_only': False, 'live': True, 'group': 'step', 'description': 'how bright',
        'alias_of': None, 'inactive': None, 'button': False}
    label = marked(Spec('label', 'inv', 'its name', choices=('inv', 'neg or not')), 'mine:Step')
    shown = control_json(label.descriptor(), ros_value('inv'))
    assert (shown['type'], shown['read_only'], shown['group']) == ('string', True, 'step')
    assert shown['menu'] == [{'value': 'inv', 'label': 'inv'},
                             {'value': 'neg or not', 'label': 'neg or not'}]
    topic = marked(Spec('topic', '/t', 'where', check=bool, accepted='a topic name'), 'mine:Step')
    assert topic.descriptor().additional_constraints == (
        'step parameter of mine:Step; accepts a topic name')
    assert control_json(topic.descriptor(), ros_value('/t'))['menu'] is None


def test_a_value_of_the_wrong_type_is_refused_before_it_reaches_the_node():
    from py_vision.viewer.camera_access import CameraError
    from py_vision.viewer.camera_panel import parameter_value
    from rcl_interfaces.msg import ParameterValue
    import pytest

    integer, switch, unknown = {'type': 'integer'}, {'type': 'bool'}, {'type': None}
    assert parameter_value('brightness', integer, 7).integer_value == 7
    # what JSON from JavaScript may hold
    assert parameter_value('brightness', integer, 7.0).integer_value == 7
    assert parameter_value('brightness', integer, -2 ** 63).integer_value == -2 ** 63
    assert parameter_value('autofocus', switch, False).type == 1
    for name, control, value in (
            ('brightness', integer, True), ('brightness', integer, 1.5),
            ('brightness', integer, '7'), ('brightness', integer, None),
            ('brightness', integer, 2 ** 63), ('autofocus', switch, 1),
            ('autofocus', switch, 'on'), ('brightness', integer, float('nan'))):
        with pytest.raises(CameraError) as refused:
            parameter_value(name, control, value)
        assert refused.value.status == 400 and name in str(refused.value)
    assert parameter_value('x', unknown, 2).type == 2
    assert parameter_value('x', unknown, True).type == 1
    assert isinstance(parameter_value('x', unknown, 'a'), ParameterValue)


def test_through_a_processing_node_the_panel_shows_the_camera_upstream(launch):
    launch('usbcam_publisher', params={'video_device': 'synthetic', 'framerate': 15.0})
    processing = launch('cv_bridge_test', params={'display': 'web', 'web_port': 0})
    own_port = int(processing.wait_for_output(URL_LINE).group(1))
    viewer = launch('usbcam_subscriber', params={'display': 'web', 'web_port': 0},
                    remaps={'usb_camera/image': 'cv_bridge_image'}, name='viewer')
    port = int(viewer.wait_for_output(URL_LINE).group(1))

    state = wait_until(lambda: (lambda s: s if s['controls'] else None)(camera(port)), 30,
                       interval=0.2, what='the camera controls behind cv_bridge_test')
    assert state['topic'] == '/cv_bridge_image'
    assert state['publisher'] == '/usbcam_publisher'
    assert state['via'] == ['/cv_bridge_test']
    assert 'cv_bridge_test' in state['message']
    assert 'brightness' in state['controls']
    # cv_bridge_test's own viewer shows the camera of its input.
    own = wait_until(lambda: (lambda s: s if s['controls'] else None)(camera(own_port)), 30,
                     interval=0.2, what="the controls in cv_bridge_test's viewer")
    assert own['publisher'] == '/usbcam_publisher' and own['via'] == []
    assert set(own['controls']) == set(state['controls'])


def test_what_the_camera_is_comes_from_its_diagnostics_when_it_publishes_them(launch, peer):
    from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
    from sensor_msgs.msg import Image
    # The peer stands in for a camera node: it publishes the topic and its diagnostics.
    peer.node.create_publisher(Image, 'usb_camera/image', 10)
    _, port, _ = start_viewer(launch)
    state = wait_until(lambda: (lambda s: s if s['publisher'] else None)(camera(port)), 30,
                       interval=0.2, what='the peer as the publisher')
    assert state['publisher'] == '/test_peer'
    wait_until(lambda: 'no camera controls' in camera(port)['message'], 15, interval=0.2,
               what='"no camera controls" for a node without them')
    assert camera(port)['camera'] == {'device': None, 'pixel_format': None, 'size': None,
                                      'fps': None, 'requested_fps': None, 'status': None,
                                      'diagnostics': False}

    diagnostics = peer.node.create_publisher(DiagnosticArray, '/diagnostics', 10)
    values = [
        KeyValue(key='device', value='/dev/video4'), KeyValue(key='pixel format', value='MJPEG'),
        KeyValue(key='size', value='1280x720'), KeyValue(key='frame rate', value='29.8'),
        KeyValue(key='requested rate', value='30.0')]
    status = DiagnosticStatus(name='test_peer: camera', hardware_id='/dev/video4', level=b'\x01',
                              message='29.8 fps, requested 30.0', values=values)
    other = DiagnosticStatus(name='someone_else: camera', values=[
        KeyValue(key='pixel format', value='YUYV')])

    def shown():
        diagnostics.publish(DiagnosticArray(status=[other, status]))
        return camera(port)['camera']['diagnostics']
    wait_until(shown, 15, interval=0.3, what='the diagnostics in GET /camera')
    assert camera(port)['camera'] == {'device': '/dev/video4', 'pixel_format': 'MJPEG',
                                      'size': '1280x720', 'fps': 29.8, 'requested_fps': 30.0,
                                      'status': 'WARN: 29.8 fps, requested 30.0',
                                      'diagnostics': True}


def test_parameters_changing_under_the_read_are_read_again_not_taken_for_no_controls(
        launch, peer):
    # A camera node whose parameters change while the panel reads them: rclpy then answers
    # a describe or a get with nothing at all (one of the names is not declared any more).
    # The panel must read again, not conclude the node has no controls (and look for a
    # camera up a pipeline that is not there).
    from rcl_interfaces.msg import IntegerRange, ParameterDescriptor, ParameterValue
    from rcl_interfaces.srv import DescribeParameters, GetParameters
    from sensor_msgs.msg import Image
    import rclpy
    node = rclpy.create_node('moving_camera', context=peer.context,
                             start_parameter_services=False)
    try:
        peer.executor.add_node(node)
        node.create_publisher(Image, 'usb_camera/image', 10)
        # It also takes images from another node (as cv_bridge_test does): a panel that took it
        # for a processing node would show that node instead.
        node.create_subscription(Image, 'upstream/image', lambda msg: None, 10)
        peer.node.create_publisher(Image, 'upstream/image', 10)
        brightness = ParameterDescriptor(
            name='brightness', type=2, additional_constraints=CONTROL_MARK,
            integer_range=[IntegerRange(from_value=-64, to_value=64, step=1)])
        short = {'describe': 1, 'get': 1}   # answers left to give short, per service

        def listed(request, response):
            response.result.names = ['brightness']
            return response

        def described(request, response):
            if short['describe']:
                short['describe'] -= 1
            else:
                response.descriptors = [brightness for _ in request.names]
            return response

        def got(request, response):
            if short['get']:
                short['get'] -= 1
            else:
                response.values = [ParameterValue(type=2, integer_value=12) for _ in request.names]
            return response
        node.create_service(ListParameters, '/moving_camera/list_parameters', listed)
        node.create_service(DescribeParameters, '/moving_camera/describe_parameters', described)
        node.create_service(GetParameters, '/moving_camera/get_parameters', got)

        _, port, _ = start_viewer(launch)
        state = wait_until(lambda: (lambda s: s if s['controls'] else None)(camera(port)), 30,
                           interval=0.2, what='the controls of moving_camera in GET /camera')
        assert short == {'describe': 0, 'get': 0}, 'both short answers were given'
        assert state['publisher'] == '/moving_camera' and state['via'] == []
        assert state['controls']['brightness']['value'] == 12
        shown = state['controls']['brightness']
        assert (shown['min'], shown['max']) == (-64, 64)
    finally:
        peer.executor.remove_node(node)
        node.destroy_node()


def test_a_call_on_its_way_when_the_node_leaves_fails_at_once_with_the_reason():
    from concurrent.futures import Future
    from py_vision.viewer.camera_panel import _Calls

    class Client:
        def __init__(self):
            self.removed = []

        def call_async(self, request):
            return Future()   # never answered: the node went away

        def remove_pending_request(self, future):
            self.removed.append(future)

    class Node:
        def __init__(self):
            self.destroyed = []

        def create_client(self, kind, name):
            return Client()

        def destroy_client(self, client):
            self.destroyed.append(client)

    node = Node()
    calls = _Calls(node, '/usbcam_publisher', timeout=3.0)
    failures, replies = [], []
    calls.call('set', object(), replies.append, lambda *failure: failures.append(failure))
    calls.expire()
    assert failures == []   # within its timeout
    calls.destroy('is no longer the camera of /usb_camera/image')
    assert failures == [(503, 'is no longer the camera of /usb_camera/image')] and replies == []
    assert len(calls.clients['set'].removed) == 1
    assert len(node.destroyed) == len(_Calls.SERVICES)
    calls.expire()
    assert len(failures) == 1, 'a failed call is not failed again'


class GraphNode:
    """
    Just enough of an rclpy node for a CameraPanel, without ROS: a graph and service clients.

    `infos` is what get_publishers_info_by_topic() answers. Every request sent is recorded in
    `sent` as (service, request, future); a service in `answers` (service -> function of the
    request) is answered at once, the others wait for the test.
    """

    def __init__(self):
        self.infos, self.sent, self.answers = [], [], {}

    def get_namespace(self):
        return '/'

    def get_name(self):
        return 'usbcam_subscriber'

    def create_guard_condition(self, callback):
        from types import SimpleNamespace
        return SimpleNamespace(trigger=callback)   # jobs run at once, on the caller's thread

    def create_subscription(self, *args, **kwargs):
        return None

    def create_timer(self, period, callback):
        return None

    def get_publishers_info_by_topic(self, topic):
        return self.infos

    def get_node_names_and_namespaces(self):
        return [(info.node_name, info.node_namespace) for info in self.infos]

    def get_logger(self):
        import logging
        return logging.getLogger('graph_node')

    def create_client(self, kind, name):
        from concurrent.futures import Future
        from types import SimpleNamespace
        service = name.rsplit('/', 1)[1]

        def call_async(request):
            future = Future()
            self.sent.append((service, request, future))
            if service in self.answers:
                future.set_result(self.answers[service](request))
            return future
        return SimpleNamespace(service_is_ready=lambda: True, call_async=call_async,
                               remove_pending_request=lambda future: None)

    def destroy_client(self, client):
        pass


def node_info(name, namespace='/'):
    from types import SimpleNamespace
    return SimpleNamespace(node_namespace=namespace, node_name=name)


def test_a_publisher_whose_node_name_is_not_discovered_yet_is_not_taken_for_the_camera():
    # The graph can list a publisher before the name of its node has arrived: it is then
    # '_NODE_NAMESPACE_UNKNOWN_/_NODE_NAME_UNKNOWN_' for a moment, not a camera to ask.
    from py_vision.viewer.camera_panel import CameraPanel
    node = GraphNode()
    panel = CameraPanel(node, '/usb_camera/image')
    node.infos = [node_info('_NODE_NAME_UNKNOWN_', '_NODE_NAMESPACE_UNKNOWN_')]
    panel._refresh()
    assert panel.describe()['publisher'] is None
    node.infos.append(node_info('usbcam_publisher'))
    panel._refresh()
    state = panel.describe()
    assert state['publisher'] == '/usbcam_publisher' and state['publishers'] == [
        '/usbcam_publisher']


def test_a_node_answering_short_again_and_again_is_read_at_the_reload_period():
    # Three reads answered short are made again at the next refreshes; after that the node is
    # read at the reload period only, not every second for ever.
    from types import SimpleNamespace
    from py_vision.viewer.camera_panel import CameraPanel, RELOAD_PERIOD_S, SHORT_READS_RETRIED
    node = GraphNode()
    node.infos = [node_info('usbcam_publisher')]
    node.answers = {
        'list_parameters': lambda request: SimpleNamespace(
            result=SimpleNamespace(names=['brightness'])),
        'describe_parameters': lambda request: SimpleNamespace(descriptors=[])}
    clock = FakeClock(0.0)
    panel = CameraPanel(node, '/usb_camera/image', clock=clock)
    reads = []
    for second in range(12):
        clock.t = float(second)
        before = len(node.sent)
        panel._refresh()
        if any(service == 'list_parameters' for service, _, _ in node.sent[before:]):
            reads.append(second)
    quick = list(range(SHORT_READS_RETRIED))   # 0, 1, 2
    assert reads == quick + [quick[-1] + RELOAD_PERIOD_S]
    assert 'changed its parameters while they were read' in panel.describe()['message']


def test_a_set_answered_with_the_wrong_number_of_results_is_a_502():
    from rcl_interfaces.msg import IntegerRange, ParameterDescriptor, ParameterValue
    from types import SimpleNamespace
    from py_vision.viewer.camera_panel import CameraPanel
    from py_vision.viewer.camera_access import CameraError
    import pytest
    node = GraphNode()
    node.infos = [node_info('usbcam_publisher')]
    brightness = ParameterDescriptor(
        name='brightness', type=2, additional_constraints=CONTROL_MARK,
        integer_range=[IntegerRange(from_value=-64, to_value=64, step=1)])
    node.answers = {
        'list_parameters': lambda request: SimpleNamespace(
            result=SimpleNamespace(names=['brightness'])),
        'describe_parameters': lambda request: SimpleNamespace(descriptors=[brightness]),
        'get_parameters': lambda request: SimpleNamespace(
            values=[ParameterValue(type=2, integer_value=0)]),
        'set_parameters': lambda request: SimpleNamespace(results=[])}
    panel = CameraPanel(node, '/usb_camera/image')
    panel._refresh()
    assert 'brightness' in panel.describe()['controls']
    with pytest.raises(CameraError) as refused:
        panel.set_controls({'brightness': 5})
    assert refused.value.status == 502
    assert 'answered 0 result(s) for 1 parameter(s)' in str(refused.value)


def test_two_nodes_with_the_camera_s_name_are_said_and_not_changed():
    # Two publishers started with the same node name: the panel would read one and the other
    # at random (device from one, format from the other), and a change would reach both.
    from types import SimpleNamespace
    from rcl_interfaces.msg import IntegerRange, ParameterDescriptor, ParameterValue
    from py_vision.viewer.camera_access import CameraError
    from py_vision.viewer.camera_panel import CameraPanel
    import pytest
    node = GraphNode()
    node.infos = [node_info('usbcam_publisher'), node_info('usbcam_publisher')]
    brightness = ParameterDescriptor(
        name='brightness', type=2, additional_constraints=CONTROL_MARK,
        integer_range=[IntegerRange(from_value=-64, to_value=64, step=1)])
    node.answers = {
        'list_parameters': lambda request: SimpleNamespace(
            result=SimpleNamespace(names=['brightness'])),
        'describe_parameters': lambda request: SimpleNamespace(descriptors=[brightness]),
        'get_parameters': lambda request: SimpleNamespace(
            values=[ParameterValue(type=2, integer_value=0)])}
    panel = CameraPanel(node, '/usb_camera/image')
    panel._refresh()
    assert '2 nodes are named /usbcam_publisher' in panel.describe()['message']
    with pytest.raises(CameraError) as refused:
        panel.set_controls({'brightness': 5})
    assert refused.value.status == 409
    assert not [sent for sent in node.sent if sent[0] == 'set_parameters']
    node.infos.pop()   # one of them renamed or stopped
    panel._refresh()
    assert 'are named' not in panel.describe()['message']


def test_a_batch_sets_the_automatic_mode_before_the_controls_it_holds(launch, peer):
    # Exposure time is held by the automatic exposure; one request switching to manual and
    # setting the time must do both, whichever order its keys come in.
    launch('usbcam_publisher', params={'video_device': 'synthetic', 'framerate': 15.0})
    subscriber, port, _ = start_viewer(launch)
    wait_until(lambda: 'exposure_time_absolute' in camera(port)['controls'], 30, interval=0.2,
               what='the exposure controls')
    menu = camera(port)['controls']['auto_exposure']['menu']
    manual = next(entry['value'] for entry in menu if 'Manual' in entry['label'])
    automatic = next(entry['value'] for entry in menu if 'Manual' not in entry['label'])
    assert post(port, {'auto_exposure': automatic})[2]['results']['auto_exposure']['applied']
    wait_until(lambda: camera(port)['controls']['exposure_time_absolute']['inactive'], 10,
               interval=0.2, what='the exposure time held by the automatic mode')
    bounds = camera(port)['controls']['exposure_time_absolute']
    wanted = bounds['min'] + bounds['step']
    status, _, answer = post(port, json.dumps({'exposure_time_absolute': wanted,
                                               'auto_exposure': manual}).encode())
    assert status == 200, answer
    assert answer['results'] == {'exposure_time_absolute': {'applied': True, 'reason': ''},
                                 'auto_exposure': {'applied': True, 'reason': ''}}
    assert value_of(get_parameters(peer, PUBLISHER, ['exposure_time_absolute'])[0]) == wanted
    assert 'Traceback' not in subscriber.output()


def test_a_string_that_is_not_text_is_refused_and_the_viewer_lives(launch, peer):
    # JSON can carry a lone UTF-16 surrogate, which no ROS string can hold: sent on as a
    # string control's value it ended the viewer's node (issue 28).
    from rcl_interfaces.msg import ParameterDescriptor
    from sensor_msgs.msg import Image
    import rclpy
    node = rclpy.create_node('text_camera', context=peer.context)
    try:
        peer.executor.add_node(node)
        node.create_publisher(Image, 'usb_camera/image', 10)
        node.declare_parameter('str_ctl', 'plain', ParameterDescriptor(
            additional_constraints=CONTROL_MARK + ', string'))
        subscriber, port, _ = start_viewer(launch)
        wait_until(lambda: 'str_ctl' in camera(port)['controls'], 30, interval=0.2,
                   what='the string control')
        for body in (b'{"str_ctl": "\\ud800"}', b'{"str_ctl": "a\\udfffb"}',
                     b'{"\\ud800": "x"}'):
            status, _, answer = post(port, body)
            assert status == 400 and 'not text' in answer['error'], (body, status, answer)
        status, _, answer = post(port, {'str_ctl': 'caf\u00e9 \u2713'})
        assert status == 200 and answer['results']['str_ctl']['applied'], answer
        assert node.get_parameter('str_ctl').value == 'caf\u00e9 \u2713'
        assert subscriber.proc.poll() is None and 'Traceback' not in subscriber.output()
    finally:
        peer.executor.remove_node(node)
        node.destroy_node()


PANEL_STEPS = """
from py_vision.params import Spec
from py_vision.steps.api import Step


class Tunable(Step):
    PARAMETERS = (
        Spec('gain', 1.0, 'how bright the output is', (0.0, 4.0), live=True),
        Spec('size', 4, 'an even size', (0, 100), live=True),
        Spec('mode', 'fast', 'how it works', choices=('fast', 'exact'), live=True),
        Spec('label', 'inv', 'what it calls itself', choices=('inv', 'neg')),
    )

    def start(self, context):
        self.logger = context.logger

    def parameters_changed(self, changes):
        if changes.get('size', 0) % 2:
            return 'size must be even'
        self.logger.info('step now has %r' % (changes,))

    def process(self, image, header):
        return image
"""


def step_env(ros_env, folder):
    """Return the node environment with the panel test's own step module on PYTHONPATH."""
    (folder / 'panel_steps.py').write_text(PANEL_STEPS)
    path = os.pathsep.join(p for p in (str(folder), ros_env.get('PYTHONPATH', '')) if p)
    return dict(ros_env, PYTHONPATH=path)


def step_state(port):
    """Return GET /camera's step once its parameters are read, else None."""
    step = camera(port)['step']
    return step if step and step['parameters'] else None


def test_a_processing_node_s_step_parameters_are_shown_and_set(
        launch, peer, ros_env, tmp_path):
    from param_client import _call
    launch('usbcam_publisher', params={'video_device': 'synthetic', 'framerate': 15.0})
    processing = launch('vision_step', params={
        'step': 'panel_steps:Tunable', 'display': 'web', 'web_port': 0},
        env=step_env(ros_env, tmp_path))
    own_port = int(processing.wait_for_output(URL_LINE).group(1))
    viewer = launch('usbcam_subscriber', params={'display': 'web', 'web_port': 0},
                    remaps={'usb_camera/image': 'vision_step/image'}, name='viewer')
    port = int(viewer.wait_for_output(URL_LINE).group(1))

    step = wait_until(lambda: step_state(port), 30, interval=0.2,
                      what="vision_step's step parameters in GET /camera")
    assert (step['node'], step['step'], step['message']) == (
        '/vision_step', 'panel_steps:Tunable', '')
    # The step's parameters and nothing else of the node, as its descriptors say.
    names = _call(peer, 'vision_step', ListParameters, 'list_parameters',
                  ListParameters.Request()).result.names
    marked = {d.name: d for d in describe_parameters(peer, 'vision_step', names)
              if d.additional_constraints.startswith('step parameter of ')}
    assert set(marked) == {'gain', 'size', 'mode', 'label'} == set(step['parameters'])
    for name, descriptor in marked.items():
        assert step['parameters'][name]['read_only'] == descriptor.read_only, name
    gain, size = step['parameters']['gain'], step['parameters']['size']
    assert (gain['type'], gain['min'], gain['max'], gain['value']) == ('double', 0.0, 4.0, 1.0)
    assert (size['type'], size['min'], size['max'], size['step']) == ('integer', 0, 100, 1)
    assert [m['value'] for m in step['parameters']['mode']['menu']] == ['fast', 'exact']
    assert step['parameters']['label']['read_only'] is True
    # The camera's controls are still the camera's, upstream.
    state = wait_until(lambda: (lambda s: s if s['controls'] else None)(camera(port)), 30,
                       interval=0.2, what='the camera controls behind vision_step')
    assert state['publisher'] == '/usbcam_publisher' and state['via'] == ['/vision_step']
    # The synthetic camera has a gain too: each keeps its own, neither list takes the other's.
    assert state['controls']['gain']['group'] == 'camera'
    assert 'mode' not in state['controls'] and 'brightness' not in step['parameters']

    # A change in the panel reaches the step.
    status, _, answer = post(port, {'gain': 2.5, 'mode': 'exact'}, path='/camera/step')
    assert status == 200, answer
    assert answer['results'] == {'gain': {'applied': True, 'reason': ''},
                                 'mode': {'applied': True, 'reason': ''}}
    processing.wait_for_output(r"step now has \{'gain': 2\.5\}")
    processing.wait_for_output(r"step now has \{'mode': 'exact'\}")
    assert [value_of(v) for v in get_parameters(peer, 'vision_step', ['gain', 'mode'])] == [
        2.5, 'exact']
    assert camera(port)['step']['parameters']['gain']['value'] == 2.5

    # Refused, each with the node's reason: out of range, by the step, read-only.
    status, _, answer = post(port, {'gain': 9.0, 'size': 3, 'label': 'neg'},
                             path='/camera/step')
    assert status == 200, answer
    results = answer['results']
    assert not any(r['applied'] for r in results.values()), results
    assert results['gain']['reason'] == set_parameter(peer, 'vision_step', 'gain', 9.0).reason
    assert 'size must be even' in results['size']['reason']
    assert results['label']['reason'] and results['label']['reason'] == set_parameter(
        peer, 'vision_step', 'label', 'neg').reason
    assert [value_of(v) for v in get_parameters(peer, 'vision_step', ['gain', 'size'])] == [
        2.5, 4]
    # Not one of its step's parameters, or of the wrong type: refused before the node.
    for bad in ({'jpeg_quality': 50}, {'brightness': 1}, {'gain': 'bright'}):
        status, _, answer = post(port, bad, path='/camera/step')
        assert status == 400 and answer['error'], (bad, answer)

    # A change made elsewhere shows.
    assert set_parameter(peer, 'vision_step', 'size', 8).successful
    wait_until(lambda: camera(port)['step']['parameters']['size']['value'] == 8, 10,
               interval=0.1, what='the size set elsewhere in GET /camera')

    # vision_step's own viewer shows its own step, and sets it through the same services.
    own = wait_until(lambda: step_state(own_port), 30, interval=0.2,
                     what="the step parameters in vision_step's own viewer")
    assert own['node'] == '/vision_step' and set(own['parameters']) == set(marked)
    status, _, answer = post(own_port, {'gain': 0.5}, path='/camera/step')
    assert status == 200 and answer['results']['gain']['applied'], answer
    processing.wait_for_output(r"step now has \{'gain': 0\.5\}")
    assert camera(own_port)['controls'], 'its own viewer shows the camera upstream too'
    for node in (viewer, processing):
        assert 'Traceback' not in node.output()


def test_without_a_processing_node_a_step_change_is_a_404(launch):
    launch('usbcam_publisher', params={'video_device': 'synthetic', 'framerate': 15.0})
    subscriber, port, _ = start_viewer(launch)
    wait_until(lambda: camera(port)['controls'], 30, interval=0.2,
               what='the controls in GET /camera')
    status, _, answer = post(port, {'gain': 1.0}, path='/camera/step')
    assert status == 404 and 'no processing node' in answer['error'], answer


def test_two_nodes_with_the_step_node_s_name_are_said_and_not_changed():
    # As for the camera's node: two nodes of one name share its parameter services.
    from types import SimpleNamespace
    from py_vision.control_descriptor import step_constraints
    from py_vision.viewer.camera_access import CameraError
    from py_vision.viewer.camera_panel import CameraPanel
    node = GraphNode()
    node.answers = {
        'list_parameters': lambda request: SimpleNamespace(
            result=SimpleNamespace(names=['gain'])),
        'describe_parameters': lambda request: SimpleNamespace(descriptors=[descriptor(
            'gain', type=3, additional_constraints=step_constraints('mine:Step'))]),
        'get_parameters': lambda request: SimpleNamespace(values=[ros_value(1.0)])}
    panel = CameraPanel(node, '/usb_camera/image', runs_step=True)
    node.infos = [node_info('usbcam_publisher'), node_info('usbcam_subscriber')]
    panel._refresh()
    step = panel.describe()['step']
    assert (step['node'], step['step'], step['message']) == (
        '/usbcam_subscriber', 'mine:Step', '')
    assert step['parameters']['gain']['value'] == 1.0
    node.infos.append(node_info('usbcam_subscriber'))
    panel._refresh()
    assert '2 nodes are named /usbcam_subscriber' in panel.describe()['step']['message']
    try:
        panel.set_step_parameters({'gain': 2.0})
    except CameraError as error:
        assert error.status == 409 and 'give each its own name' in str(error)
    else:
        raise AssertionError('a change reaching two nodes was sent')
    assert not any(service == 'set_parameters' for service, _, _ in node.sent)
