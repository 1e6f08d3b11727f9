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
The installed vision_step node end to end: a user's own step, load errors, a failing step.

The user's steps are a module written to a temporary folder on PYTHONPATH, as a user's own
package would put it there.
"""

import os
from pathlib import Path
import re
import shutil
import signal

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
import numpy as np
from param_client import describe_parameters, set_parameter
import pytest
from rclpy.qos import QoSProfile, ReliabilityPolicy
from ros_harness import status_values, wait_until
from sensor_msgs.msg import Image
from std_msgs.msg import String

RELIABLE = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)
OUTPUT = 'vision_step/image'
PROCESSING = 'vision_step: processing'  # the node's status in /diagnostics
TESTS = Path(__file__).resolve().parents[1]  # user_steps.py, the user's own steps


@pytest.fixture
def user_env(ros_env, tmp_path):
    """Return the node environment with the user's step modules on PYTHONPATH, a bad model."""
    shutil.copy(TESTS / 'user_steps.py', tmp_path)
    (tmp_path / 'broken_steps.py').write_text('import no_such_dependency_xyz\n')
    model = tmp_path / 'truncated.tflite'
    model.write_bytes(b'TFL3' + bytes(100))
    path = os.pathsep.join(p for p in (str(tmp_path), ros_env.get('PYTHONPATH', '')) if p)
    return dict(ros_env, PYTHONPATH=path, USER_STEP_MODEL=str(model))


def image_msg(image, stamp_sec, frame_id):
    msg = Image()
    msg.header.stamp.sec = stamp_sec
    msg.header.frame_id = frame_id
    msg.height, msg.width = image.shape[:2]
    msg.encoding = 'bgr8'
    msg.step = image.shape[1] * 3
    msg.data = image.tobytes()
    return msg


def as_bgr(msg):
    assert msg.encoding == 'bgr8' and msg.step == msg.width * 3
    return np.frombuffer(bytes(msg.data), np.uint8).reshape(msg.height, msg.width, 3)


class Probe:
    """Publishes to usb_camera/image and collects vision_step/image."""

    def __init__(self, peer):
        self.publisher = peer.node.create_publisher(Image, 'usb_camera/image', RELIABLE)
        self.received = peer.collect(Image, OUTPUT, RELIABLE)

    def send(self, image, stamp_sec, frame_id='cam'):
        self.publisher.publish(image_msg(image, stamp_sec, frame_id))

    def wait_connected(self):
        """Publish a warm-up image until its result comes back (discovery is done)."""
        warm_up = np.zeros((8, 8, 3), np.uint8)

        def answered():
            self.send(warm_up, 999)
            return any(m.header.stamp.sec == 999 for m in self.received)
        wait_until(answered, 20.0, interval=0.2, what='vision_step to answer')

    def result_for(self, stamp_sec, timeout=10.0):
        def find():
            return next((m for m in self.received if m.header.stamp.sec == stamp_sec), None)
        return wait_until(find, timeout, what='the output for stamp %d' % stamp_sec)


def test_a_users_step_processes_publishes_and_takes_its_parameters(launch, peer, user_env):
    said = peer.collect(String, 'user_step/said', RELIABLE)
    node = launch('vision_step', params={'step': 'user_steps:Invert', 'gain': 2.0},
                  env=user_env)
    line = node.wait_for_output(r'running step user_steps:Invert .*').group(0)
    assert 'publishing them on /vision_step/image; gain 2, label inv' in line, line
    probe = Probe(peer)
    probe.wait_connected()
    image = np.random.default_rng(1).integers(0, 256, (90, 120, 3), np.uint8)
    probe.send(image, 1, 'frame_1')
    out = probe.result_for(1)
    assert out.header.frame_id == 'frame_1'
    assert (as_bgr(out) == 255 - image).all()
    # None publishes nothing: frame 2 was processed (the step said so), only frame 3 came out.
    probe.send(image, 2, 'nothing')
    wait_until(lambda: any(m.data == 'nothing gain 2' for m in said), 10.0,
               what='the step to see frame 2')
    probe.send(image, 3, 'frame_3')
    probe.result_for(3)
    assert not any(m.header.stamp.sec == 2 for m in probe.received)
    # Its parameters are the node's, with their types, ranges and choices.
    gain, label = describe_parameters(peer, 'vision_step', ['gain', 'label'])
    assert not gain.read_only and gain.description == 'how bright the inverted image is'
    assert (gain.floating_point_range[0].from_value,
            gain.floating_point_range[0].to_value) == (0.0, 4.0)
    # Marked as the step's (the viewer's panel lists them), with the choices.
    assert label.read_only and label.additional_constraints == (
        'step parameter of user_steps:Invert; one of: inv | neg')
    # A live change reaches it; a value out of range does not.
    assert set_parameter(peer, 'vision_step', 'gain', 3.0).successful
    probe.send(image, 4, 'frame_4')
    wait_until(lambda: any(m.data == 'frame_4 gain 3' for m in said), 10.0,
               what='the step to use gain 3')
    refused = set_parameter(peer, 'vision_step', 'gain', 9.0)
    assert not refused.successful
    assert node.stop(signal.SIGINT) == 0
    assert 'Traceback' not in node.output()


def test_the_smallest_step_is_any_class_with_process(launch, peer, user_env):
    node = launch('vision_step', params={'step': 'user_steps:Plain'}, env=user_env)
    probe = Probe(peer)
    probe.wait_connected()
    image = np.random.default_rng(2).integers(0, 256, (64, 80, 3), np.uint8)
    probe.send(image, 1)
    assert (as_bgr(probe.result_for(1)) == image[:, ::-1]).all()
    assert node.stop(signal.SIGINT) == 0


def test_a_users_own_model_timed_with_model_time_shows_as_the_models_time(
        launch, peer, user_env):
    arrays = peer.collect(DiagnosticArray, '/diagnostics', RELIABLE)
    node = launch('vision_step', params={'step': 'user_steps:OwnModel'}, env=user_env)
    probe = Probe(peer)
    probe.wait_connected()
    image = np.zeros((48, 64, 3), np.uint8)

    def split_reported():
        probe.send(image, 1)
        values = status_values(arrays, PROCESSING)
        return values if values.get('models p50 ms') not in (None, '', '0.0') else None
    values = wait_until(split_reported, 30.0, interval=0.2, what='the models time reported')
    assert float(values['models p50 ms']) >= 50.0, values
    assert float(values['rest p50 ms']) < float(values['models p50 ms']), values
    assert float(values['processing p50 ms']) >= float(values['models p50 ms']), values
    assert node.stop(signal.SIGINT) == 0


def test_help_lists_the_steps_parameters(launch, user_env):
    node = launch('vision_step', extra_args=['--help', '--ros-args', '-p',
                                             'step:=user_steps:Invert'], env=user_env)
    assert node.wait_exit(20) == 0
    out = node.output()
    assert out.startswith('usage: ros2 run py_vision vision_step')
    assert 'gain (double, 0..4; default 1.0; settable live)' in out, out
    assert "label (string, inv or neg; default 'inv')" in out, out
    assert 'threads (integer, 1..64; default 1)' in out, out
    # Without a step: the default one, circle, and its parameter.
    plain = launch('vision_step', extra_args=['--help'], env=user_env)
    assert plain.wait_exit(20) == 0
    assert 'simulated_work_ms (double, 0..10000' in plain.output()


@pytest.mark.parametrize('step, words', [
    ('squares', "step 'squares': not a built-in step (circle, hand_signs, faces)"),
    ('no_such_module_xyz:Step', 'no module no_such_module_xyz on PYTHONPATH'),
    ('user_steps:Missing', "step 'user_steps:Missing': module user_steps has no Missing"),
    ('user_steps:NotAStep', 'user_steps:NotAStep is not a step'),
    ('user_steps:BadInit', 'creating BadInit failed: RuntimeError: no licence key'),
    ('broken_steps:Any', 'importing module broken_steps failed: ModuleNotFoundError: No module '
                         "named 'no_such_dependency_xyz'"),
    ('user_steps:BadModel', 'truncated.tflite'),
])
def test_a_step_that_cannot_be_loaded_is_one_line_and_status_1(launch, user_env, step, words):
    node = launch('vision_step', params={'step': step}, env=user_env)
    assert node.wait_exit(30) == 1
    out = node.output()
    lines = [line for line in out.splitlines() if line.strip()]
    assert len(lines) == 1, out
    assert 'ERROR' in lines[0] and words in lines[0], out
    assert 'Traceback' not in out


WARN, ERROR = DiagnosticStatus.WARN, DiagnosticStatus.ERROR
LEVELS = {WARN: 'WARN', ERROR: 'ERROR'}
FAILED_LINE = re.compile(r'step user_steps:Failing failed on a frame in process '
                         r'\(\S+/user_steps.py:\d+\): ValueError: cannot read frame \d+; .*'
                         r'\((\d+) failed so far\)')


def test_a_step_that_raises_is_logged_counted_and_the_node_goes_on(launch, peer, user_env):
    arrays = peer.collect(DiagnosticArray, '/diagnostics', RELIABLE)
    node = launch('vision_step', params={'step': 'user_steps:Failing'}, env=user_env)
    probe = Probe(peer)
    probe.wait_connected()
    image = np.zeros((40, 40, 3), np.uint8)
    stamp = [1000]

    def status(level):
        # The newest processing status at `level`.
        for array in reversed(list(arrays)):
            for found in array.status:
                if found.name == 'vision_step: processing' and found.level == level:
                    return found
        return None

    def send_then(level, frame_ids):
        # One frame a call, so that none replaces another before the step takes it.
        def sent():
            stamp[0] += 1
            probe.send(image, stamp[0], frame_ids[stamp[0] % len(frame_ids)])
            return status(level)
        return wait_until(sent, 40.0, interval=0.1,
                          what='the processing status %s' % LEVELS[level])
    # Every other frame fails: WARN, naming the failure.
    warn = send_then(WARN, ['bad', 'good'])
    assert 'failed on' in warn.message and 'ValueError: cannot read frame' in warn.message
    arrays.clear()
    # Every frame fails: ERROR.
    error = send_then(ERROR, ['bad'])
    assert 'failed on every frame lately' in error.message, error.message
    values = {kv.key: kv.value for kv in error.values}
    assert int(values['step failed']) >= 2
    # Once per kind and period: far fewer lines than failures, the count running on.
    counts = [int(n) for n in FAILED_LINE.findall(node.output())]
    assert counts and counts[0] == 1, node.output()
    assert len(counts) < int(values['step failed']) / 2
    # A wrong return value is a failure of its own kind.
    probe.send(image, 1, 'wrong')
    node.wait_for_output(r'process\(\) returned a str, not a bgr8 image')
    # And the node goes on.
    probe.send(image, 2, 'good')
    probe.result_for(2)
    assert node.stop(signal.SIGINT) == 0
    assert 'Traceback' not in node.output()


def test_the_image_goes_out_only_while_someone_subscribes(launch, peer):
    arrays = peer.collect(DiagnosticArray, '/diagnostics', RELIABLE)
    node = launch('vision_step')  # circle
    publisher = peer.node.create_publisher(Image, 'usb_camera/image', RELIABLE)
    image = np.zeros((90, 120, 3), np.uint8)
    sent = [0]

    def send_until(condition, what):
        def sent_one():
            if condition():
                return True
            sent[0] += 1
            publisher.publish(image_msg(image, sent[0], 'cam'))
            return False
        wait_until(sent_one, 60.0, interval=0.1, what=what)
    # Nobody subscribes to vision_step/image: the frames are processed, none is published.
    send_until(lambda: int(status_values(arrays, PROCESSING).get('processed', 0)) >= 5,
               'five processed frames')
    assert status_values(arrays, PROCESSING)['images published'] == '0'
    # A subscriber arriving late gets frames, and the node counts them.
    received = peer.collect(Image, OUTPUT, RELIABLE)
    send_until(lambda: received, 'an image for the late subscriber')
    assert as_bgr(received[0])[60, 60].tolist() == [0, 0, 255]  # the circle's red
    assert received[0].header.frame_id == 'cam'
    send_until(lambda: int(status_values(arrays, PROCESSING).get('images published', 0)) >= 1,
               'the count of images published')
    assert node.stop(signal.SIGINT) == 0
