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
A USB camera beside a capture node of another driver: the kernel's vivid in the VM.

vivid is a real kernel capture device (/dev/video0, driver vivid) that comes first; an
emulated UVC camera is plugged in beside it, in the VM, at /dev/video40 (its library loaded
with LD_PRELOAD, so the publisher runs as a program of its own there, not forked from the VM's
agent as vivid's other tests' nodes are). `--list-devices` names both with their drivers and
`video_device:=auto` opens the USB camera.
"""

import tempfile

from emulated_camera import EmulatedCamera
from ros_harness import NodeProcess, wait_until

# The emulated CPU takes tens of seconds to start an interpreter and import rclpy.
SLOW = 200.0


def beside_vivid(vm):
    """In the VM: the emulated webcam beside vivid; what --list-devices and auto give."""
    camera = EmulatedCamera(tempfile.mkdtemp(prefix='py_vision_uvc_'), 'webcam_1080p', 40)
    env = camera.env(vm.env)
    try:
        listing = NodeProcess('usbcam_publisher', ['--list-devices'], env, 'list_devices')
        status = listing.wait_exit(SLOW)
        node = NodeProcess('usbcam_publisher', [
            '--ros-args', '-p', 'video_device:=auto', '-p', 'image_width:=320',
            '-p', 'image_height:=240', '-p', 'framerate:=5.0'], env, 'auto')
        opened = node.wait_for_output(r'opened auto \((/dev/video\d+)\)', SLOW).group(1)
        wait_until(lambda: camera.frames_served > 0, SLOW, what='frames from the USB camera')
        holds_vivid = vm.open_by(node.proc.pid)
        stopped = node.stop(timeout=60)
        return {'status': status, 'listing': listing.output(), 'opened': opened,
                'stopped': stopped, 'holds_vivid': holds_vivid, 'output': node.output()}
    finally:
        camera.close()


def test_list_devices_names_vivid_and_the_usb_camera_and_auto_opens_the_usb_camera(
        vivid, emulated_camera):
    # Built here, where the compiler is quick: the VM finds the library and the pictures in
    # the cache it shares.
    emulated_camera(model='webcam_1080p', node=40)
    got = vivid.run(beside_vivid)
    assert got['status'] == 0, got['listing']
    lines = {line.split(':', 1)[0]: line for line in got['listing'].splitlines()
             if line.startswith('/dev/video')}
    assert 'driver vivid' in lines['/dev/video0'] and 'formats YUYV' in lines['/dev/video0']
    assert 'video_device:=auto' not in lines['/dev/video0']
    usb = lines['/dev/video40']
    assert 'Emu Webcam 1080p, driver uvcvideo' in usb and 'by-id /dev/v4l/by-id/usb-' in usb
    assert usb.endswith('video_device:=auto opens it'), usb
    assert got['opened'] == '/dev/video40', got['output']
    assert not got['holds_vivid'], 'the node keeps vivid open'
    assert got['stopped'] == 0 and 'Traceback' not in got['output']
