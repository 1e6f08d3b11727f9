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
The `main()` every py_vision executable shares: start-up, spin and a quiet, clean exit.

- ``--help`` / ``-h`` prints the node's parameters and exits 0 without starting anything.
- Malformed ``--ros-args`` are one error line and exit status 2.
- Bad configuration (ConfigError) is one error line and exit status 1.
- Ctrl-C (SIGINT) and SIGTERM end the node with status 0 and no traceback, at any moment of
  start-up or shutdown. The first signal stops the node; further ones (`ros2 launch` sends its
  own SIGINT after the terminal's) are ignored, so the clean-up always runs to its end.
"""

import os
import signal
import sys
import tempfile
import threading

from py_vision import dds
from py_vision.params import ConfigError, help_text
import rclpy
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.logging import get_logger

__all__ = ['ConfigError', 'main_for', 'run']


class _Stopping:
    """What the process-level signal handler knows: whether rclpy took over, and stop requests."""

    rclpy_up = False
    requested = False
    cleaning = False


def _on_signal(signum, frame):
    _Stopping.requested = True
    if not _Stopping.rclpy_up:
        # Still starting (or already shut down): nothing of ours to clean up yet, or the
        # clean-up is running in `finally` below and must not be cut short.
        if not _Stopping.cleaning:
            raise SystemExit(0)
    # Otherwise rclpy's own handler, which runs first, has shut the context down: spin()
    # returns and the node closes; raising here would cut that clean-up short.


def install_quiet_signals():
    """Make SIGINT and SIGTERM end this process quietly (called while the package imports)."""
    if threading.current_thread() is threading.main_thread():
        for sig in (signal.SIGINT, signal.SIGTERM):
            signal.signal(sig, _on_signal)


def _wants_help(argv):
    # Anywhere on the line: a parameter value is part of its `name:=value` word.
    return any(arg in ('-h', '--help') for arg in argv[1:])


def _init_rclpy(argv):
    """
    Initialise rclpy with argv; return None, or what is wrong with the arguments in one line.

    rcl prints its own lines about bad arguments before it raises: they are held back and
    replaced by one line, and printed as they were when initialisation succeeds.
    """
    sys.stderr.flush()
    saved = os.dup(2)
    with tempfile.TemporaryFile() as held:
        os.dup2(held.fileno(), 2)
        try:
            rclpy.init(args=argv)
            error = None
        except Exception as failure:  # rclpy's own RCLError types for bad arguments
            lines = [line for line in str(failure).splitlines() if line.strip()]
            error = lines[0] if lines else type(failure).__name__
            # rcl appends where in its sources the parse failed: not for users.
            error = error.split('. Error:')[0].replace('failed to initialize rcl: ', '')
            if 'UnknownROSArgs' in type(failure).__name__:
                error = 'unknown ROS arguments %s' % error
        finally:
            sys.stderr.flush()
            os.dup2(saved, 2)
            os.close(saved)
        if error is None:
            held.seek(0)
            os.write(2, held.read())
    return error


def _shutdown_quietly():
    try:
        rclpy.try_shutdown()
    except Exception:  # a signal shut rclpy down between its check and ours
        pass


def run(node_class, args=None):
    """
    Build node_class() and spin it until Ctrl-C, SIGTERM or rclpy shutdown; return the status.

    node_class has NODE_NAME, PARAMETERS (a tuple of params.Spec) and SUMMARY for --help, and
    PUBLISHES (what it publishes, see dds.segment_size); it
    raises ConfigError for problems the user has to fix, has a close() that releases what it
    holds (threads, devices, sockets) and copes with a half-built node, and sets `failed` when
    it stops because of an error. It may have a classmethod variant(), called once rclpy is
    up, that returns the class to build instead (usbcam_publisher: its lifecycle node).
    """
    argv = list(sys.argv if args is None else args)
    if _wants_help(argv):
        sys.stdout.write(help_text(node_class.NODE_NAME, node_class.PARAMETERS,
                                   node_class.SUMMARY))
        return 0
    install_quiet_signals()
    # Ctrl-C and SIGTERM wait while rclpy starts and the node is built: rclpy shutting its
    # context down while another thread creates a service or a timer can deadlock. Blocked
    # here, in the main thread, before any other thread exists, the signals stay pending in
    # every thread (DDS's and the node's inherit the mask) until the node spins.
    _hold_signals(True)
    # The shared-memory segment is sized to what the node publishes, before parameters exist.
    dds.use_packaged_profile(node_class.PUBLISHES, argv, node_class.NODE_NAME)
    error = _init_rclpy(argv)
    if error is not None:
        if _Stopping.requested:
            return 0
        sys.stderr.write('%s: invalid command line arguments: %s (see --help)\n' % (
            node_class.NODE_NAME, error))
        _shutdown_quietly()
        return 2
    # Made now, while rclpy runs: an executor first made after a signal has shut rclpy down
    # is left half-built, and Python complains about it at exit.
    executor = SingleThreadedExecutor()
    _Stopping.rclpy_up = True
    node = None
    built = False
    status = 0
    try:
        # A node class may build a variant of itself chosen by its parameters (variant()).
        node_class = getattr(node_class, 'variant', lambda: node_class)()
        # The object exists before its __init__ (which opens devices and ports) so that an
        # interrupted start-up can still be cleaned up.
        node = node_class.__new__(node_class)
        node.__init__()
        built = True
        executor.add_node(node)
        _hold_signals(False)  # a signal that came meanwhile is handled now
        executor.spin()
    except ConfigError as error:
        logger = node.get_logger() if _has_logger(node) else get_logger(node_class.NODE_NAME)
        logger.error(str(error))
        status = 1
    except (KeyboardInterrupt, ExternalShutdownException, SystemExit):
        pass
    except Exception:
        if rclpy.ok() and not _Stopping.requested:
            raise
        # rclpy was shut down by a signal while the node was being built or was spinning.
    finally:
        _Stopping.cleaning = True
        _Stopping.rclpy_up = False
        _ignore_signals()
        _hold_signals(False)  # pending ones are ignored now
        if node is not None:
            node.close()
            if built:
                node.destroy_node()
        try:
            executor.shutdown()
        except Exception:  # rclpy already tore it down with its context
            pass
        _shutdown_quietly()
    if getattr(node, 'failed', False):
        status = 1
    return status


def _hold_signals(hold):
    """Block (hold pending) or unblock SIGINT and SIGTERM in the calling thread."""
    how = signal.SIG_BLOCK if hold else signal.SIG_UNBLOCK
    signal.pthread_sigmask(how, {signal.SIGINT, signal.SIGTERM})


def _ignore_signals():
    """Ignore SIGINT and SIGTERM from now on: the node is stopping and must finish doing so."""
    # SIG_IGN, unlike a Python handler, survives the interpreter's finalisation, which
    # otherwise puts the default action back while DDS participants are still being torn down.
    if threading.current_thread() is threading.main_thread():
        for sig in (signal.SIGINT, signal.SIGTERM):
            signal.signal(sig, signal.SIG_IGN)


def _has_logger(node):
    try:
        node.get_logger()
    except Exception:  # the node's own __init__ had not got as far as rclpy's
        return False
    return True


def main_for(node_class):
    """Return a console_scripts entry point for node_class."""
    def main(args=None):
        sys.exit(run(node_class, args))
    main.__doc__ = 'Run the %s node.' % node_class.NODE_NAME
    return main
