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
The usbcam_publisher executable: the plain camera node, or its lifecycle node.

`ros2 run py_vision usbcam_publisher` builds usbcam_publisher.USBImagePublisher; with
`-p managed:=true` (command line, parameter file or launch) it builds
managed_publisher.ManagedPublisher instead. The choice is read the way the node itself will
read its parameters, once rclpy is up.
"""

from py_vision.managed_publisher import ManagedPublisher
from py_vision.node_main import main_for
from py_vision.params import read_given
from py_vision.usbcam_publisher import MANAGED, USBImagePublisher


def publisher_class() -> type:
    """Return the class to build: the lifecycle node when the parameter managed is true."""
    if read_given(USBImagePublisher.NODE_NAME, MANAGED):
        return ManagedPublisher
    return USBImagePublisher


main = main_for(USBImagePublisher, variant=publisher_class)


if __name__ == '__main__':
    main()
