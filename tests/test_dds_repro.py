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
How bench/dds_discovery_repro.py tells a caught shared-memory port from a failed read.

Fast DDS 2.6.0 to 2.6.5 can stop reading a shared-memory port for good (docs/boards.md): the
same read then fails again and again until the node ends. With the fix a read fails once for
each message whose sender has gone, and the port goes on working. The reproduction reads a
node's log: Fast DDS' warning for each failed read, after a time stamp in local time to the
millisecond, and the node's line saying when it was told to stop (wall clock).
"""

import datetime
import importlib.util
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


def repro():
    """Return the reproduction script as a module (it runs nothing when imported)."""
    spec = importlib.util.spec_from_file_location(
        'dds_discovery_repro', REPO / 'bench' / 'dds_discovery_repro.py')
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def stamp(seconds):
    """Return the time stamp Fast DDS writes for a moment seconds after 05:06:07 (local)."""
    moment = datetime.datetime(2026, 3, 4, 5, 6, 7) + datetime.timedelta(seconds=seconds)
    return moment.strftime('%Y-%m-%d %H:%M:%S.%f')[:-3]


def wall(seconds):
    """Return the wall-clock time seconds after 05:06:07 (local), as the node prints it."""
    moment = datetime.datetime(2026, 3, 4, 5, 6, 7) + datetime.timedelta(seconds=seconds)
    return moment.timestamp()


def failed_read(seconds):
    """Return Fast DDS 2.6.0's warning for a failed read of a shared-memory port, as written."""
    return ('\x1b[37;1m%s \x1b[33;1m[\x1b[37;1mRTPS_MSG_OUT\x1b[33;1m Warning] \x1b[37mError '
            'receiving data: No such file or directory - 0x555c3d7e98b0 (0x555c3d7e9940)'
            '\x1b[34;1m -> Function \x1b[36mReceive\x1b[m\n' % stamp(seconds))


def told_to_stop(seconds):
    """Return the node's line saying when it was told to stop."""
    return '4801.20 told to stop at %.3f (wall clock); 12 messages from other nodes\n' % (
        wall(seconds))


def test_failed_reads_that_go_on_until_the_node_stops_are_a_caught_port():
    # Fast DDS 2.6.0 once caught: thousands of failures a second, with short pauses under load.
    log = ('4800.30 up\n' + ''.join(failed_read(0.25 * step) for step in range(12))
           + told_to_stop(3.0) + failed_read(3.1) + '4801.52 stopped\n')
    assert repro().port_caught(log) == (13, True)


def test_a_burst_of_failed_reads_then_none_is_not_a_caught_port():
    # The fixed Fast DDS: one failure for each message left by a sender that has gone.
    log = ''.join(failed_read(0.001 * step) for step in range(23)) + '4800.30 up\n' + (
        told_to_stop(2.0))
    assert repro().port_caught(log) == (23, False)


def test_a_pause_in_the_failed_reads_is_not_a_caught_port():
    log = failed_read(0.0) + failed_read(0.1) + failed_read(1.5) + told_to_stop(1.6)
    assert repro().port_caught(log) == (3, False)


def test_failed_reads_just_before_the_stop_are_not_a_caught_port():
    # A burst as the node stops tells nothing about the port: too short to count.
    log = failed_read(1.8) + failed_read(1.9) + told_to_stop(2.0) + failed_read(2.1)
    assert repro().port_caught(log) == (3, False)


def test_a_line_of_the_node_written_inside_a_fast_dds_line_is_read():
    # Fast DDS writes a line in pieces; the node's print may come between them.
    pieces = failed_read(0.0).split(' \x1b[33;1m[', 1)
    log = (pieces[0] + ' \x1b[33;1m' + told_to_stop(0.9) + '[' + pieces[1]
           + ''.join(failed_read(0.1 * step) for step in range(1, 9)))
    assert repro().port_caught(log) == (9, True)


def test_a_node_that_did_not_say_when_it_was_told_to_stop_counts_as_caught():
    # Killed, or crashed, before it said so: nothing shows that its port was read again.
    assert repro().port_caught('4800.30 up\n' + failed_read(0.0)) == (1, True)


def test_no_failed_read_no_caught_port():
    assert repro().port_caught('4800.30 up\n' + told_to_stop(1.0)) == (0, False)
