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
same read then fails thousands of times a second until the node ends. With the fix a read fails
once for each message whose sender has gone, and the port goes on working. The reproduction
counts Fast DDS' warning for a failed read in the node's log.
"""

import importlib.util
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
FAILED_READ = ('\x1b[37;1m2026-12-04 21:23:22.826 \x1b[33;1m[\x1b[37;1mRTPS_MSG_OUT\x1b[33;1m '
               'Warning] \x1b[37mError receiving data: No such file or directory - 0x5570d0d35840 '
               '(0x5570d0d358d0)\x1b[34;1m -> Function \x1b[36mReceive\x1b[m\n')


def _load_repro():
    """Return the reproduction script as a module (it runs nothing when imported)."""
    spec = importlib.util.spec_from_file_location(
        'dds_discovery_repro', REPO / 'bench' / 'dds_discovery_repro.py')
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


port_caught = _load_repro().port_caught


def test_reads_failing_in_a_loop_are_a_caught_port():
    # Fast DDS 2.6.0 once caught: 3000 to 11000 failures a second in these runs.
    log = '7674.34 up\n' + FAILED_READ * 6408 + '7675.57 stopped\n'
    assert port_caught(log) == (6408, True)


def test_a_burst_of_failed_reads_is_not_a_caught_port():
    # The fixed Fast DDS: one failure for each message of a sender that has gone (up to 77 in
    # a node in these runs; a port holds 512).
    log = FAILED_READ * 23 + '7674.34 up\n' + FAILED_READ * 512 + '7674.57 stopped\n'
    assert port_caught(log) == (535, False)


def test_a_failed_read_split_by_a_print_of_the_node_is_counted():
    # Fast DDS writes a line in pieces; the node's print may come between them.
    head, tail = FAILED_READ.split('\x1b[37mError', 1)
    log = head + '7674.44 sees repro_0_23\n\x1b[37mError' + tail
    assert port_caught(FAILED_READ * 1024 + log) == (1025, True)


def test_no_failed_read_no_caught_port():
    assert port_caught('7674.34 up\n7674.57 stopped\n') == (0, False)
