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
Ctrl-C and SIGTERM end every node every time, whatever was asked of it before (a stress test).

Each executable, many times over: start it, set, get and describe parameters over its
services as `ros2 param` does (values it takes and values it refuses), then send SIGINT or
SIGTERM at a random moment after the last answer. Every round must end within a bounded wait,
with status 0 and the node's last line saying it stopped. The executables run their rounds
at the same time (LANES), as in the pipeline, frames flowing from the cameras to the others.

Nothing here is timed: the waits are bounds a healthy node never comes near, and the random
moment only moves where the signal falls. The rounds are many enough to catch a node that
ignores one signal in three with a probability of 1 - (2/3)**ROUNDS per lane (98% for 10);
PY_VISION_STOP_ROUNDS asks for more (a soak).

On the boards' Fast DDS 2.6.0 (Humble), a process that listens on shared memory can stop
hearing for good when a process that sent to it exits before it read the message (docs/boards.md,
"A node nobody hears"). py_vision's nodes listen there on UDP, but for the readers of their
images, so each of their starts must be reached, as on Jazzy. The test's own peers listen on
shared memory as any rclpy process does: a peer that hears nothing is replaced by a new one,
which must reach the node (each replacement is named in a warning).
"""

import os
import random
import signal
import subprocess
import threading
import time
import warnings

from param_client import describe_parameters, get_parameters, set_parameter, Unreached
import ros_harness

ROUNDS = int(os.environ.get('PY_VISION_STOP_ROUNDS', '10'))
# A node that is still running this long after the signal ignored it.
STOP_BOUND_S = 20.0

RUNNABLE = {
    'usbcam_publisher': {'video_device': 'synthetic', 'framerate': 30.0},
    'usbcam_subscriber': {'display': 'none', 'stats_period': 1.0},
    'cv_bridge_test': {'display': 'none'},
}
# What `ros2 param set` would send: values each node takes, and values it refuses.
SETS = {
    'usbcam_publisher': [('brightness', 20), ('brightness', 500), ('jpeg_quality', 70),
                         ('frame_id', 'camera_round'), ('brightness', 'bright')],
    'usbcam_subscriber': [('stats_period', 2.0), ('stats_period', -1.0),
                          ('stats_period', 1.0)],
    'cv_bridge_test': [('simulated_work_ms', 1.0), ('simulated_work_ms', -5.0),
                       ('simulated_work_ms', 0.0)],
}
READ = {
    'usbcam_publisher': ['brightness', 'jpeg_quality', 'frame_id', 'video_device'],
    'usbcam_subscriber': ['stats_period', 'display', 'image_transport'],
    'cv_bridge_test': ['simulated_work_ms', 'display', 'image_transport'],
}
# The rounds run in lanes at the same time, each (executable, node name, remappings): two
# cameras, as on a stereo rig, whose publisher spends most of its time idle in rcl_wait,
# where a lost wake-up leaves it; the processing node and the viewer receive their frames.
LANES = [
    ('usbcam_publisher', 'usbcam_publisher', {}),
    ('usbcam_publisher', 'usbcam_publisher_right',
     {'__node': 'usbcam_publisher_right', 'usb_camera/image': 'usb_camera_right/image'}),
    ('usbcam_subscriber', 'usbcam_subscriber', {}),
    ('cv_bridge_test', 'cv_bridge_test', {}),
]
# What a node logs while it cleans up, before node_main's last line.
CLEANED_UP = {'usbcam_publisher': 'camera released after'}


class LanePeer:
    """A lane's parameter client (node_peer), replaced by a new one when it hears nothing."""

    def __init__(self, domain_id, name):
        self.domain_id, self.name, self.count = domain_id, name, 0
        self.deaf = []  # why each replaced peer was found deaf
        self.node_peer = ros_harness.RosPeer(domain_id, name=name)

    def replace(self, why=None):
        """Close this peer and take a new one; why: the reason it was found deaf, if it was."""
        if why is not None:
            self.deaf.append(why)
        deaf, self.node_peer = self.node_peer, None
        deaf.close()
        self.count += 1
        self.node_peer = ros_harness.RosPeer(self.domain_id, name='%s_%d' % (
            self.name, self.count))

    def call(self, call, node_name, *args, why=''):
        """
        Return what the call answers; on Humble, through a new peer if this one hears nothing.

        The node listens on UDP there (but for its images): when the call gets no answer it is
        the peer that hears nothing (its own shared-memory port stopped). A new peer must reach
        the node.
        """
        try:
            return call(self.node_peer, node_name, *args)
        except Unreached as error:
            if not ros_harness.ON_HUMBLE:
                raise
            self.replace('%s: %s' % (why, error))
            return call(self.node_peer, node_name, *args)

    def close(self):
        """Close the current peer."""
        if self.node_peer is not None:
            self.node_peer.close()


def one_round(lane, number, rng, env, peer):
    """Run one round; return None, or what went wrong with the node's log."""
    executable, node_name, remaps = lane
    sig = rng.choice([signal.SIGINT, signal.SIGTERM])
    node = ros_harness.NodeProcess(
        executable, ros_harness.ros_args(RUNNABLE[executable], remaps), env,
        name='%s_%d' % (node_name, number))
    try:
        why = '%s round %d' % (node_name, number)
        for name, value in SETS[executable]:
            peer.call(set_parameter, node_name, name, value, why=why)
        peer.call(get_parameters, node_name, READ[executable], why=why)
        peer.call(describe_parameters, node_name, READ[executable], why=why)
        delay = rng.uniform(0.0, 0.5)
        time.sleep(delay)  # the random moment itself, not a synchronisation
        what = '%s round %d, %s %.2f s after the last parameter call' % (
            node_name, number, signal.Signals(sig).name, delay)
        if node.proc.poll() is not None:
            return '%s: exited with %s before the signal\n%s' % (
                what, node.proc.returncode, node.tail())
        node.proc.send_signal(sig)
        try:
            status = node.proc.wait(STOP_BOUND_S)
        except subprocess.TimeoutExpired:
            log = node.tail()
            # Not a second signal: with rclpy's own handler that one would wake it.
            os.killpg(node.proc.pid, signal.SIGKILL)
            node.proc.wait()
            return '%s: still running %.0f s after the signal (ignored it; killed)\n%s' % (
                what, STOP_BOUND_S, log)
        lines = node.output().splitlines()
        stopped = 'stopped by %s' % signal.Signals(sig).name
        if status != 0 or not lines or stopped not in lines[-1]:
            return '%s: exit status %s, last line %r (expected status 0 and %r)\n%s' % (
                what, status, lines[-1] if lines else '', stopped, node.tail())
        if executable in CLEANED_UP and CLEANED_UP[executable] not in node.output():
            return '%s: no %r line\n%s' % (what, CLEANED_UP[executable], node.tail())
        return None
    except (AssertionError, Unreached) as error:  # a parameter call went unanswered
        return '%s round %d: %s\n%s' % (node_name, number, error, node.tail())
    finally:
        node.kill()


def test_every_node_stops_on_every_signal_after_parameter_calls(ros_env, domain_id):
    seed = random.randrange(1 << 30)
    failures = []
    deaf = []

    def rounds(lane):
        node_name = lane[1]
        peer = None
        try:
            rng = random.Random('%d %s' % (seed, node_name))
            peer = LanePeer(domain_id, 'param_client_%s' % node_name)
            for number in range(ROUNDS):
                failure = one_round(lane, number, rng, ros_env, peer)
                if failure:
                    # The lane ends here: a killed node's DDS participant outlives it until
                    # its lease expires, and would answer for the next round's discovery.
                    failures.append("%s (the lane's other rounds were not run)" % failure)
                    return
        except Exception as error:  # the test's own peer failed: say so, do not hang
            failures.append('%s: %s: %s' % (node_name, type(error).__name__, error))
        finally:
            if peer is not None:
                deaf.extend(peer.deaf)
                peer.close()

    threads = [threading.Thread(target=rounds, args=(lane,)) for lane in LANES]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    if deaf:
        warnings.warn('Fast DDS 2.6.0: %d test peer(s) stopped hearing, each replaced by a new '
                      'one that reached the node (docs/boards.md, "A node nobody hears"):\n%s'
                      % (len(deaf), '\n'.join(deaf)))
    assert not failures, '%d of %d lanes failed (seed %d, %d rounds a lane):\n\n%s' % (
        len(failures), len(LANES), seed, ROUNDS, '\n\n'.join(failures))
