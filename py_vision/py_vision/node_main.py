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

import signal
import sys
import threading

from py_vision import dds
from py_vision.params import ConfigError, help_text
import rclpy
from rclpy.executors import ExternalShutdownException
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
    user_args = argv[1:]
    if '--ros-args' in user_args:
        user_args = user_args[:user_args.index('--ros-args')]
    return any(arg in ('-h', '--help') for arg in user_args)


def _shutdown_quietly():
    try:
        rclpy.try_shutdown()
    except Exception:  # a signal shut rclpy down between its check and ours
        pass


def run(node_class, args=None):
    """
    Build node_class() and spin it until Ctrl-C, SIGTERM or rclpy shutdown; return the status.

    node_class has NODE_NAME, PARAMETERS (a tuple of params.Spec) and SUMMARY for --help; it
    raises ConfigError for problems the user has to fix, has a close() that releases what it
    holds (threads, devices, sockets) and copes with a half-built node, and sets `failed` when
    it stops because of an error.
    """
    argv = list(sys.argv if args is None else args)
    if _wants_help(argv):
        sys.stdout.write(help_text(node_class.NODE_NAME, node_class.PARAMETERS,
                                   node_class.SUMMARY))
        return 0
    install_quiet_signals()
    dds.use_packaged_profile()
    try:
        rclpy.init(args=argv)
    except Exception as error:  # rclpy raises its own RCLError types for bad arguments
        if _Stopping.requested:
            return 0
        message = str(error).strip().splitlines()
        sys.stderr.write('%s: invalid command line arguments: %s\n' % (
            node_class.NODE_NAME, message[0] if message else type(error).__name__))
        _shutdown_quietly()
        return 2
    _Stopping.rclpy_up = True
    node = None
    built = False
    status = 0
    try:
        # The object exists before its __init__ (which opens devices and ports) so that an
        # interrupted start-up can still be cleaned up.
        node = node_class.__new__(node_class)
        node.__init__()
        built = True
        rclpy.spin(node)
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
        if node is not None:
            node.close()
            if built:
                node.destroy_node()
        _shutdown_quietly()
    if getattr(node, 'failed', False):
        status = 1
    return status


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
