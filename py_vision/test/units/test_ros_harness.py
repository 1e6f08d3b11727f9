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


"""The tests' own harness: what its helpers promise the tests that use them."""

import signal
import sys

import pytest
import ros_harness


def test_a_peer_stops_spinning_before_its_node_is_destroyed(domain_id):
    # A peer whose executor thread still spins while its node is destroyed raises
    # InvalidHandle in that thread (seen as a warning in a fresh-clone run).
    peer = ros_harness.RosPeer(domain_id)
    spinning_at_destroy = []
    destroy = peer.node.destroy_node

    def recorded_destroy():
        spinning_at_destroy.append(peer._thread.is_alive())
        return destroy()

    peer.node.destroy_node = recorded_destroy
    peer.close()
    assert spinning_at_destroy == [False]


def test_a_node_ended_by_a_signal_is_named_by_it_in_its_log_tail(tmp_path):
    # A node that crashes as it stops (Fast DDS 2.6's teardown SIGSEGV, docs/boards.md) must
    # read as such in the failing test, not as "exit status -11".
    script = ('import os, resource, signal; resource.setrlimit(resource.RLIMIT_CORE, (0, 0)); '
              'print("closing", flush=True); os.kill(os.getpid(), signal.SIGSEGV)')
    proc = ros_harness.NodeProcess(sys.executable, ['-c', script], dict(ros_harness.plain_env()),
                                   name='crashing', log_dir=str(tmp_path))
    status = proc.wait_exit(timeout=20.0)
    assert status == -11
    tail = proc.tail()
    assert '(ended by SIGSEGV)' in tail and 'closing' in tail, tail
    assert 'exit status' not in tail
    assert ros_harness.signal_name(2) == 'SIGINT'
    assert ros_harness.signal_name(200) == 'signal 200'


# A program that waits and leaves stopping to Python's defaults, as Humble's `ros2 launch` leaves
# Ctrl-C to Python's own SIGINT handler: Python installs that handler only where SIGINT was not
# ignored at its start.
WAITS = 'import time; print("waiting", flush=True); time.sleep(60)'


@pytest.mark.parametrize('sig', ros_harness.STOP_SIGNALS, ids=lambda sig: sig.name)
def test_a_process_it_starts_stops_on_a_signal_the_tests_ignore(tmp_path, sig):
    # scripts/test.sh started by a script in the background (a non-interactive shell's `&`)
    # runs the tests with SIGINT ignored, nohup with SIGHUP: the processes the tests start
    # must still stop on it, as the same command typed at a terminal does.
    with ros_harness.signals_ignored(sig):
        proc = ros_harness.NodeProcess(sys.executable, ['-c', WAITS],
                                       dict(ros_harness.plain_env()), name='waiting',
                                       log_dir=str(tmp_path))
    try:
        proc.wait_for_output('waiting')
        assert proc.stop(sig, timeout=10.0) == -sig, proc.tail()
    finally:
        proc.kill()


def test_signals_ignored_gives_back_what_was_there():
    before = [signal.getsignal(sig) for sig in ros_harness.STOP_SIGNALS]
    with ros_harness.signals_ignored(*ros_harness.STOP_SIGNALS):
        assert all(signal.getsignal(sig) is signal.SIG_IGN for sig in ros_harness.STOP_SIGNALS)
    assert [signal.getsignal(sig) for sig in ros_harness.STOP_SIGNALS] == before
