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

Bad configuration ends the process with one error line and exit status 1. Ctrl-C (SIGINT) and
SIGTERM end it with status 0 and no traceback, also while it is still starting up.
"""

import sys

from py_vision import dds
import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.logging import get_logger


class ConfigError(Exception):
    """A parameter or a device the user gave cannot be used; the message says which and why."""


def run(node_class, args=None):
    """
    Build node_class() and spin it until Ctrl-C, SIGTERM or rclpy shutdown; return the status.

    node_class must raise ConfigError for problems the user has to fix, have a close() that
    releases what it holds (threads, devices, sockets) and copes with a half-built node, and
    set `failed` when it stops because of an error.
    """
    # A signal is first handled by rclpy, which shuts its context down, then passed on to the
    # handler py_vision/__init__.py installed for the executables: SystemExit(0) in the main
    # thread, wherever it is. So the clean-up is in `finally`, and the node object exists
    # (__new__) before its __init__, which opens devices and ports, can be interrupted.
    dds.use_packaged_profile()
    rclpy.init(args=args)
    node = None
    built = False
    status = 0
    try:
        node = node_class.__new__(node_class)
        node.__init__()
        built = True
        rclpy.spin(node)
    except ConfigError as error:
        get_logger(node_class.NODE_NAME).error(str(error))
        status = 1
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except Exception:
        if rclpy.ok():
            raise
        # rclpy was shut down by a signal while the node was being built.
    finally:
        if node is not None:
            node.close()
            if built:
                node.destroy_node()
        rclpy.try_shutdown()  # also cleans up after a node interrupted half-built
    if getattr(node, 'failed', False):
        status = 1
    return status


def main_for(node_class):
    """Return a console_scripts entry point for node_class."""
    def main(args=None):
        sys.exit(run(node_class, args))
    main.__doc__ = 'Run the %s node.' % node_class.NODE_NAME
    return main
