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
- Ctrl-C (SIGINT), SIGTERM and SIGHUP (a closed terminal) end the node with status 0, no
  traceback and, once it was built, a last line `stopped by SIGINT` after its clean-up, whatever
  it was doing when the signal came.
- Nothing that arrives over ROS ends a node: an exception raised by a callback (a malformed
  request in rclpy's own parameter service, a defect in the node's) is one error line per kind
  and minute (`CallbackFailures`), and the node goes on.
  The first signal stops the node; further ones (`ros2 launch` sends its own SIGINT after the
  terminal's) are ignored, so the clean-up always runs to its end.
- A node's command (``usbcam_publisher --list-formats``) interrupted by a signal ends
  at once, without a traceback, with the shell's status for it (130 for SIGINT, 143 for
  SIGTERM): unlike a node, whose normal end is a signal, the command did not finish its work.

How a signal reaches the executor (docs/internals.md says why it is done this way): rclpy's own
handler is not installed. Python's C-level handler, in whichever thread the kernel picks,
writes the signal's number to a pipe (signal.set_wakeup_fd); a thread reading that pipe
triggers a guard condition of the node, which wakes the executor; the main thread, between two
callbacks, sees the request and stops spinning, then closes the node and shuts rclpy down
itself. Nothing shuts rclpy down behind the main thread's back.
"""

import os
import signal
import sys
import tempfile
import threading
import time
from typing import Callable, ClassVar, Dict, List, Optional, Protocol, Sequence, Tuple, Type

from py_vision import dds, ros_arguments, transport
from py_vision.callback_failures import CallbackFailures
from py_vision.params import ConfigError, help_text, Spec
import rclpy
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.logging import get_logger
from rclpy.signals import SignalHandlerOptions

__all__ = ['ConfigError', 'main_for', 'NodeProgram', 'run']

# What stops a node: Ctrl-C, `kill` or a service manager, a closed terminal or ssh session.
STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)


class NodeProgram(Protocol):
    """
    What run() needs of a node class (an rclpy Node) and of the node it builds.

    The class says what --help prints (NODE_NAME, PARAMETERS, SUMMARY; a classmethod
    help_parameters(argv), where it has one, lists them instead), what it publishes
    before rclpy starts (PUBLISHES: dds.NO_IMAGES, OWN_SIZE or INPUT_SIZE, which sizes its
    shared memory), the base topic whose images it reads, as it subscribes to it (IMAGE_INPUT,
    None for none: on Fast DDS 2.6 the node receives through shared memory on that topic's
    transports alone, everything else through UDP) and its own commands (COMMANDS: a flag such
    as '--list-formats' -> a function of the command line returning the exit status, run
    instead of the node).
    Built with no arguments, the node raises ConfigError for anything the user has to fix;
    close() releases what it holds (threads, devices, sockets) and copes with a half-built node;
    `failed` is set when it stops because of an error (the exit status is then 1).
    """

    NODE_NAME: ClassVar[str]
    PARAMETERS: ClassVar[Sequence[Spec]]
    SUMMARY: ClassVar[str]
    PUBLISHES: ClassVar[str]
    IMAGE_INPUT: ClassVar[Optional[str]]
    COMMANDS: ClassVar[Dict[str, Callable[[List[str]], int]]]
    failed: bool

    def __init__(self) -> None: ...  # noqa: D107

    def close(self) -> None: ...  # noqa: D102

    def get_logger(self): ...  # noqa: D102 (rclpy Node's)

    def create_guard_condition(self, callback): ...  # noqa: D102 (rclpy Node's)

    def destroy_node(self) -> None: ...  # noqa: D102 (rclpy Node's)


class _Stopping:
    """What the signal handling knows: the first signal received, and whom to wake for it."""

    signum = None
    wake = None  # triggers the running node's stop guard condition


def _on_signal(signum, frame):
    # Runs in the main thread between two bytecodes, maybe inside rclpy's own Python code:
    # it only records the request (and wakes the executor, which is thread-safe), it never
    # raises. The main thread stops at its next check, after the code it was running.
    _request_stop(signum)


def _request_stop(signum):
    if _Stopping.signum is None:
        _Stopping.signum = signum
    wake = _Stopping.wake
    if wake is not None:
        wake()


def install_quiet_signals():
    """Make the stop signals requests to stop, which run() carries out (main thread only)."""
    if threading.current_thread() is threading.main_thread():
        for sig in STOP_SIGNALS:
            signal.signal(sig, _on_signal)


class _Interrupted(Exception):
    """A node command was interrupted by a signal."""


def _interrupt(signum, frame):
    _ignore_signals()
    raise _Interrupted(signum)


def _run_command(command, argv):
    """Run a node's command; a signal ends it quietly with status 128 + the signal's number."""
    if threading.current_thread() is not threading.main_thread():
        return command(argv)
    try:
        for sig in STOP_SIGNALS:
            signal.signal(sig, _interrupt)
        return command(argv)
    except _Interrupted as stop:
        return 128 + stop.args[0]
    finally:
        _ignore_signals()  # what is left is the exit


class SignalWatch:
    """
    Wake an executor for the stop signals, whichever thread the kernel delivers them to.

    Python runs a signal's handler in the main thread only, and only between two bytecodes:
    never while that thread sleeps in rcl_wait. Its C-level handler, which runs at once in
    whatever thread took the signal, writes the signal's number to the wakeup fd; this
    object's thread reads it and triggers `guard` (a guard condition of the spinning node),
    so the executor wakes. Made and closed in the main thread.
    """

    def __init__(self, guard):
        self._guard = guard
        self._read, self._write = os.pipe()
        os.set_blocking(self._write, False)  # set_wakeup_fd's requirement
        self._previous = signal.set_wakeup_fd(self._write)
        self._thread = threading.Thread(target=self._watch, name='signal_watch', daemon=True)
        self._thread.start()

    def _watch(self):
        while True:
            try:
                data = os.read(self._read, 64)
            except OSError:
                return
            if not data:  # close(): the write end is gone
                return
            _request_stop(data[0])
            try:
                self._guard.trigger()
            except Exception:  # the node is being destroyed: it is stopping anyway
                pass

    def close(self):
        """Stop writing to the pipe and end the thread."""
        signal.set_wakeup_fd(self._previous)
        os.close(self._write)
        self._thread.join()
        os.close(self._read)


def _wants_help(argv):
    # Anywhere on the line: a parameter value is part of its `name:=value` word.
    return any(arg in ('-h', '--help') for arg in argv[1:])


def _help_parameters(node_class, argv) -> Sequence[Spec]:
    """Return what --help lists: PARAMETERS, or what help_parameters(argv) says where defined."""
    # Optional: a node whose parameters depend on its command line (vision_step: its step's).
    more = getattr(node_class, 'help_parameters', None)
    return node_class.PARAMETERS if more is None else more(argv)


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
            # Signals are node_main's (run()): rclpy's handler would shut the context
            # down from its own thread, behind the executor's back.
            rclpy.init(args=argv, signal_handler_options=SignalHandlerOptions.NO)
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
    except Exception:  # the node shut rclpy down itself between its check and ours
        pass


def run(node_class: Type[NodeProgram], args=None) -> int:
    """
    Build node_class() and spin it until a stop signal or rclpy shutdown; return the status.

    node_class is what NodeProgram describes.
    """
    argv = list(sys.argv if args is None else args)
    if _wants_help(argv):
        sys.stdout.write(help_text(node_class.NODE_NAME, _help_parameters(node_class, argv),
                                   node_class.SUMMARY))
        return 0
    # A node's own commands (COMMANDS: flag -> function(argv) -> exit status) run instead of
    # the node, without a ROS graph: usbcam_publisher --list-formats.
    for flag, command in node_class.COMMANDS.items():
        if flag in argv[1:]:
            return _run_command(command, argv)
    # From here a signal is a request, carried out at the next of the checks below: rclpy
    # starting or the node being built is never cut short (a context shut down while a
    # service or a timer is being created can deadlock), and what was built is closed.
    install_quiet_signals()
    # The shared-memory segment is sized to what the node publishes, before parameters exist.
    image_topics = _image_topics(node_class, argv)
    dds.use_packaged_profile(node_class.PUBLISHES, argv, node_class.NODE_NAME,
                             image_topics=image_topics)
    # rclpy gets the parameters in py_vision's order (ros_arguments), whatever its own.
    with ros_arguments.rclpy_arguments(argv, node_class.NODE_NAME) as rclpy_argv:
        error = _init_rclpy(rclpy_argv)
    if error is not None:
        if _Stopping.signum is not None:
            return 0
        sys.stderr.write('%s: invalid command line arguments: %s (see --help)\n' % (
            node_class.NODE_NAME, error))
        _shutdown_quietly()
        return 2
    executor = SingleThreadedExecutor()
    node = None
    built = False
    watch = None
    status = 0
    try:
        # The object exists before its __init__ (which opens devices and ports) so that a
        # start-up that fails half-way (ConfigError) can still be cleaned up.
        if _Stopping.signum is None:  # else: stopped before there was anything to build
            node = node_class.__new__(node_class)
            node.__init__()
            built = True
            _check_transport(node, image_topics)
            executor.add_node(node)
            stop_guard = node.create_guard_condition(lambda: None)
            _Stopping.wake = stop_guard.trigger
            watch = SignalWatch(stop_guard)
            _spin(executor, CallbackFailures(node.get_logger()))
    except ConfigError as error:
        logger = node.get_logger() if _has_logger(node) else get_logger(node_class.NODE_NAME)
        logger.error(str(error))
        status = 1
    except ExternalShutdownException:  # the node shut rclpy down itself (a fatal error)
        pass
    except Exception:
        if rclpy.ok() and _Stopping.signum is None:
            raise
        # rclpy was shut down under the executor (a node ending itself on a fatal error).
    finally:
        _ignore_signals()
        _Stopping.wake = None
        if watch is not None:
            watch.close()
        if node is not None:
            node.close()
            if built:
                # On Fast DDS 2.6 the node's last frames stay readable a moment (dds.LINGER_S):
                # its participant, and with it its shared memory, ends with the node.
                time.sleep(dds.linger_s())
                node.destroy_node()
        try:
            executor.shutdown()
        except Exception:  # rclpy already tore it down with its context
            pass
        if built and _Stopping.signum is not None:
            node.get_logger().info('stopped by %s' % signal.Signals(_Stopping.signum).name)
        _shutdown_quietly()
    if node is not None and built and node.failed:
        status = 1
    return status


def _image_topics(node_class: Type[NodeProgram], argv: Sequence[str]) -> Tuple[str, ...]:
    """Return the topics, as rcl will resolve them, that node_class may read images on."""
    if node_class.IMAGE_INPUT is None:
        return ()
    name = ros_arguments.node_name(argv, node_class.NODE_NAME)
    raw, *others = transport.image_topics(
        ros_arguments.topic_name(argv, node_class.IMAGE_INPUT, name))
    # The others are subscribed to by their full name (the base's, resolved, and a suffix),
    # which rcl resolves again: a rule for /base/compressed applies to it.
    return (raw,) + tuple(ros_arguments.topic_name(argv, topic, name) for topic in others)


_IMAGE_TYPES = ('Image', 'CompressedImage', 'CompressedVideo')


def _check_transport(node, image_topics: Tuple[str, ...]) -> None:
    """
    Say what of dds' profile did not hold, once the node exists (Fast DDS 2.6 only).

    An error when the UDP port its endpoints were given was taken by another process before
    Fast DDS bound it (nobody can then reach the node); a warning for an image subscription on a
    topic dds did not give shared memory (its frames come through UDP).
    """
    port = dds.lost_port()
    if port is not None:
        node.get_logger().error(
            'UDP port %d, on which this node receives everything but images, was taken by '
            'another process as the node started: nothing (ros2 param, the panel, the graph) '
            'can reach it; restart it (docs/boards.md, "A node nobody hears")' % port)
    if not dds.shm_topics():
        return
    for subscription in node.subscriptions:
        if (subscription.msg_type.__name__ in _IMAGE_TYPES
                and subscription.topic_name not in image_topics):
            node.get_logger().warning(
                'frames on %s come through UDP, not shared memory: on Fast DDS 2.6 only the '
                'topics read off the command line (%s) are (docs/boards.md, "A node nobody '
                'hears")' % (subscription.topic_name, ', '.join(image_topics[:2])))


def _spin(executor, failures: CallbackFailures):
    """Spin until a signal is received or rclpy is shut down; a failing callback is logged."""
    # spin_once() returns after every callback, the stop guard's included; the guard, which
    # a signal triggers, only wakes an idle executor.
    while _Stopping.signum is None and executor.context.ok():
        try:
            executor.spin_once()
        except ExternalShutdownException:
            raise
        except Exception as error:  # raised by a callback (spin_once passes it on)
            if _Stopping.signum is not None or not executor.context.ok():
                raise  # rclpy shut down under the executor: run() handles it
            failures.record(error)


def _ignore_signals():
    """Ignore the stop signals from now on: the node is stopping and must finish doing so."""
    # SIG_IGN, unlike a Python handler, survives the interpreter's finalisation, which
    # otherwise puts the default action back while DDS participants are still being torn down.
    if threading.current_thread() is threading.main_thread():
        for sig in STOP_SIGNALS:
            signal.signal(sig, signal.SIG_IGN)


def _has_logger(node):
    try:
        node.get_logger()
    except Exception:  # the node's own __init__ had not got as far as rclpy's
        return False
    return True


def main_for(node_class: Type[NodeProgram]) -> Callable[..., None]:
    """Return the console_scripts entry point of node_class."""
    def main(args=None):
        sys.exit(run(node_class, args))
    main.__doc__ = 'Run the %s node.' % node_class.NODE_NAME
    return main
