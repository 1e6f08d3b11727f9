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
The browser viewer in a real browser: headless Chromium watching the installed nodes.

Needs Playwright (pip install playwright: it has no rosdep key) and Debian's `chromium` package
(or CHROMIUM=/path/to/chromium): the `browser` fixture (conftest.py) skips the test with the
reason without either on a developer's PC or in `colcon test`, and fails it when CI=true.
"""

import base64

import cv2
import numpy as np
from py_vision.capture.synthetic_picture import read_frame_index
from ros_harness import wait_until

URL_LINE = r'viewer at (http://[^\s/]+:\d+/)'


def shown_frame(page):
    """Return the frame the video element holds now (BGR), drawn at its natural size."""
    data_url = page.evaluate("""() => {
        const video = document.getElementById('video');
        const canvas = document.createElement('canvas');
        canvas.width = video.naturalWidth;
        canvas.height = video.naturalHeight;
        canvas.getContext('2d').drawImage(video, 0, 0);
        return canvas.toDataURL('image/png');
    }""")
    png = base64.b64decode(data_url.split(',', 1)[1])
    return cv2.imdecode(np.frombuffer(png, np.uint8), cv2.IMREAD_COLOR)


def stat(page, name):
    return page.locator('#stat-' + name).inner_text()


def test_browser_shows_the_live_video_and_stats(launch, browser):
    publisher = launch('usbcam_publisher', params={'video_device': 'synthetic',
                                                   'framerate': 15.0})
    subscriber = launch('usbcam_subscriber', params={'display': 'web', 'web_port': 0})
    url = subscriber.wait_for_output(URL_LINE).group(1)

    page = browser.new_page()
    page.goto(url)
    video = page.locator('#video')
    wait_until(lambda: video.evaluate('e => e.naturalWidth') > 0, 20.0, interval=0.1,
               what='the first frame in the browser')
    assert video.evaluate('e => [e.naturalWidth, e.naturalHeight]') == [640, 480]

    # The picture moves on: the frame index the synthetic source paints into every frame,
    # read back from what the browser draws, increases.
    first = shown_frame(page)
    assert first.shape == (480, 640, 3)
    first_index = read_frame_index(first)
    assert first_index is not None, 'the browser does not show a synthetic frame'
    wait_until(lambda: (read_frame_index(shown_frame(page)) or 0) > first_index, 10.0,
               interval=0.2, what='the shown frame to change')

    # The stats panel is filled and keeps updating.
    wait_until(lambda: stat(page, 'fps') not in ('', '-') and float(stat(page, 'fps')) > 0,
               15.0, interval=0.2, what='a positive fps in the page')
    assert stat(page, 'resolution').replace(' ', '') == '640\u00d7480'
    assert stat(page, 'encoding') == 'bgr8'
    assert stat(page, 'topic') == '/usb_camera/image'
    assert stat(page, 'clients') == '1'
    frames = int(stat(page, 'frames'))
    wait_until(lambda: int(stat(page, 'frames')) > frames, 10.0, interval=0.2,
               what='the frame count in the page to go up')
    assert page.locator('#status').inner_text() == 'live'

    # Stopping the node while a browser watches is quick and clean.
    assert subscriber.stop() == 0
    assert 'Traceback' not in subscriber.output()
    wait_until(lambda: page.locator('#status').inner_text() == 'disconnected', 10.0,
               interval=0.2, what='the page to notice that the node stopped')
    publisher.stop()


def test_moving_a_camera_control_in_the_panel_changes_the_stream(launch, peer, browser):
    from param_client import get_parameters
    launch('usbcam_publisher', params={'video_device': 'synthetic', 'framerate': 15.0})
    # As on a headless board: on every interface, so the viewer wants its token.
    subscriber = launch('usbcam_subscriber', params={'display': 'web', 'web_port': 0,
                                                     'web_host': '0.0.0.0'})
    port, token = subscriber.wait_for_output(
        r'viewer at http://[^\s/]+:(\d+)/\?token=([\w.~-]+)').groups()
    clean = 'http://127.0.0.1:%s/' % port

    page = browser.new_page()
    assert page.goto(clean).status == 401
    page.goto(clean + '?token=' + token)
    assert page.url == clean, 'the token stays in the address bar'
    slider = page.locator('#input-brightness')
    slider.wait_for(state='visible', timeout=30000)
    wait_until(lambda: page.locator('#video').evaluate('e => e.naturalWidth') > 0, 20.0,
               interval=0.1, what='the first frame in the browser')
    assert page.locator('#cam-node').inner_text() == '/usbcam_publisher'
    assert page.locator('#cam-device').inner_text() == 'synthetic'
    before = shown_frame(page).mean()

    # A real click on the slider, 60% along: the value there is the slider's own (its range
    # is the one the publisher's descriptor gives).
    low, high = (float(slider.get_attribute(name)) for name in ('min', 'max'))
    box = slider.bounding_box()
    page.mouse.click(box['x'] + box['width'] * 0.6, box['y'] + box['height'] / 2)
    value = int(slider.input_value())
    assert value > (low + high) / 2
    wait_until(lambda: get_parameters(peer, 'usbcam_publisher', ['brightness'])[0]
               .integer_value == value, 10, interval=0.1,
               what='brightness %d on the publisher' % value)
    assert page.locator('#control-brightness .note').inner_text() == ''
    # The synthetic camera adds brightness to the luma: the picture gets brighter.
    wait_until(lambda: shown_frame(page).mean() > before + 0.5 * value, 10, interval=0.2,
               what='the shown frame to get brighter (mean was %.1f)' % before)
    assert page.locator('#control-brightness .value').inner_text() == str(value)

    # A menu (the synthetic camera's auto exposure) shows its entry once, in the menu itself,
    # and its name on one line, as the slider controls' names are.
    menu = page.locator('#input-auto_exposure')
    assert menu.evaluate('e => e.options[e.selectedIndex].text') == 'Aperture Priority Mode'
    assert not page.locator('#control-auto_exposure .value').is_visible()
    line = page.locator('#control-brightness label').bounding_box()['height']
    assert page.locator('#control-auto_exposure label').bounding_box()['height'] == line


def test_controls_named_as_javascript_object_properties_work(launch, peer, browser):
    # The page keys controls by the names the camera's node gives them: names such as
    # constructor, toString or __proto__ are controls like any other (issue 28).
    from rcl_interfaces.msg import IntegerRange, ParameterDescriptor
    from sensor_msgs.msg import Image
    import rclpy
    names = ('constructor', 'toString', '__proto__', 'hasOwnProperty')
    node = rclpy.create_node('odd_camera', context=peer.context)
    try:
        peer.executor.add_node(node)
        node.create_publisher(Image, 'usb_camera/image', 10)
        for name in names:
            node.declare_parameter(name, 3, ParameterDescriptor(
                additional_constraints='camera control', integer_range=[
                    IntegerRange(from_value=0, to_value=10, step=1)]))
        subscriber = launch('usbcam_subscriber', params={'display': 'web', 'web_port': 0})
        url = subscriber.wait_for_output(URL_LINE).group(1)
        page = browser.new_page()
        posts = []
        page.on('request', lambda request: posts.append(request.post_data)
                if request.method == 'POST' else None)
        page.goto(url, wait_until='domcontentloaded')   # no frames: the video never loads
        errors = []
        page.on('pageerror', lambda error: errors.append(str(error)))
        try:
            for name in names:
                page.locator('#input-' + name).wait_for(state='attached', timeout=30000)
        except Exception:
            raise AssertionError('the controls are not all shown: %r; page errors: %s; %s' % (
                page.locator('#panel').inner_text(), errors, page.evaluate(
                    'async () => (await fetch("/camera")).text()')))
        assert page.locator('#controls .control').count() == len(names)
        for value, name in enumerate(names, start=5):
            posts.clear()
            page.locator('#input-' + name).evaluate(
                '(e, v) => { e.value = String(v); e.dispatchEvent(new Event("input")); }', value)
            wait_until(lambda: node.get_parameter(name).value == value, 10, interval=0.1,
                       what='%s set to %d from the page' % (name, value))
            wait_until(lambda: page.locator('#control-%s .value' % name).inner_text() ==
                       str(value), 10, interval=0.1, what='the page to show %s' % name)
            assert posts == ['{"%s":%d}' % (name, value)], posts[:5]
        assert subscriber.proc.poll() is None and 'Traceback' not in subscriber.output()
    finally:
        peer.executor.remove_node(node)
        node.destroy_node()


def test_the_panel_shows_and_sets_the_processing_step_s_parameters(launch, peer, browser):
    # cv_bridge_test's own viewer: the camera's controls, and below them its step's parameter.
    from param_client import describe_parameters, get_parameters
    launch('usbcam_publisher', params={'video_device': 'synthetic', 'framerate': 15.0})
    processing = launch('cv_bridge_test', params={'display': 'web', 'web_port': 0})
    url = processing.wait_for_output(URL_LINE).group(1)
    page = browser.new_page()
    page.goto(url, wait_until='domcontentloaded')
    slider = page.locator('#input-step-simulated_work_ms')
    slider.wait_for(state='visible', timeout=30000)
    page.locator('#input-brightness').wait_for(state='visible', timeout=30000)
    assert page.locator('#step-title').inner_text() == 'step circle on /cv_bridge_test'
    bounds = describe_parameters(peer, 'cv_bridge_test', ['simulated_work_ms'])[0] \
        .floating_point_range[0]
    assert (float(slider.get_attribute('min')), float(slider.get_attribute('max'))) == (
        bounds.from_value, bounds.to_value)
    assert page.locator('#step .control').count() == 1

    slider.evaluate('e => { e.value = "20"; e.dispatchEvent(new Event("input")); }')
    wait_until(lambda: get_parameters(peer, 'cv_bridge_test', ['simulated_work_ms'])[0]
               .double_value == 20.0, 10, interval=0.1,
               what='simulated_work_ms 20 on cv_bridge_test')
    wait_until(lambda: page.locator('#control-step-simulated_work_ms .value').inner_text() ==
               '20', 10, interval=0.1, what='the page to show the step parameter at 20')
    assert page.locator('#control-step-simulated_work_ms .note').inner_text() == ''
    assert processing.proc.poll() is None and 'Traceback' not in processing.output()


def test_a_value_on_its_way_to_the_node_is_not_put_back_by_a_poll(launch, peer, browser):
    # The panel polls /camera about once a second. A value the user set is on its way (its POST
    # unanswered) when a poll answer still holds the old one: the slider keeps what the user set
    # (once seen put back on a loaded machine, where the node took a while to answer).
    from param_client import get_parameters
    launch('usbcam_publisher', params={'video_device': 'synthetic', 'framerate': 15.0})
    subscriber = launch('usbcam_subscriber', params={'display': 'web', 'web_port': 0})
    url = subscriber.wait_for_output(URL_LINE).group(1)
    page = browser.new_page()
    held = []  # the POSTs of control values, held back until the test lets them go
    page.route('**/camera/controls', lambda route: held.append(route)
               if route.request.method == 'POST' else route.continue_())
    polls = []
    page.on('response', lambda response: polls.append(response)
            if response.url.endswith('/camera') else None)
    page.goto(url)
    slider = page.locator('#input-brightness')
    slider.wait_for(state='visible', timeout=30000)
    before = slider.input_value()
    low, high = (float(slider.get_attribute(name)) for name in ('min', 'max'))
    box = slider.bounding_box()
    page.mouse.click(box['x'] + box['width'] * 0.8, box['y'] + box['height'] / 2)
    value = slider.input_value()
    assert value != before and float(value) > (low + high) / 2
    # (page.evaluate lets Playwright deliver the page's events to this thread.)
    wait_until(lambda: page.evaluate('1') and held, 10, interval=0.05,
               what="the slider's POST")
    # Two poll answers after the POST left: both say the node still has the old value.
    seen = len(polls)
    wait_until(lambda: page.evaluate('1') and len(polls) >= seen + 2, 10, interval=0.1,
               what='two polls of /camera')
    assert get_parameters(peer, 'usbcam_publisher', ['brightness'])[0].integer_value == int(
        before), 'the node took the value before the test let it go'
    assert slider.input_value() == value, 'a poll put the old value back while it was sent'
    # Let it go: the node takes it, and the slider and the value shown agree with it.
    for route in held:
        route.continue_()
    wait_until(lambda: get_parameters(peer, 'usbcam_publisher', ['brightness'])[0]
               .integer_value == int(value), 10, interval=0.1,
               what='brightness %s on the publisher' % value)
    wait_until(lambda: page.evaluate('1') and page.locator('#control-brightness .value')
               .inner_text() == value, 10, interval=0.1, what='the value shown')
    assert slider.input_value() == value
