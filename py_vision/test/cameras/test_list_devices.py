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
The right camera on a board: `--list-devices`, and `video_device:=auto` opening the USB camera.

A board's own capture pipeline registers /dev/video nodes too, often before the USB camera's:
here an emulated one (`pipeline_node`: driver xilinx-vipp, not on USB, no by-id link) at
/dev/video40, before two emulated UVC cameras.
"""

import re

from ros_harness import wait_until


def cameras(emulated_camera):
    pipeline = emulated_camera(model='pipeline_node', node=40)
    webcam = emulated_camera(model='webcam_1080p', node=41)
    vga = emulated_camera(model='vga_yuyv', node=43)
    return pipeline, webcam, vga


def env_of(ros_env, *devices):
    env = ros_env
    for device in devices:
        env = device.env(env)
    return env


def test_every_device_in_one_line_with_driver_card_bus_links_and_formats(
        launch, emulated_camera, ros_env):
    pipeline, webcam, vga = cameras(emulated_camera)
    node = launch('usbcam_publisher', extra_args=['--list-devices'],
                  env=env_of(ros_env, pipeline, webcam, vga))
    assert node.wait_exit(20) == 0, node.output()
    lines = {line.split(':', 1)[0]: line for line in node.output().splitlines()
             if line.startswith('/dev/video')}
    assert sorted(lines) == ['/dev/video40', '/dev/video41', '/dev/video43'], node.output()
    assert lines['/dev/video40'] == (
        '/dev/video40: vcap_mipi output 0, driver xilinx-vipp, platform:vcap_mipi:0, by-path '
        '/dev/v4l/by-path/platform-vcap_mipi-video-index0, formats YUYV')
    assert lines['/dev/video41'] == (
        '/dev/video41: Emu Webcam 1080p, driver uvcvideo, %s, by-id %s, by-path %s, '
        'formats YUYV MJPG, video_device:=auto opens it' % (
            webcam.bus_info, webcam.by_id, webcam.by_path))
    assert lines['/dev/video43'] == (
        '/dev/video43: Emu VGA Camera, driver uvcvideo, %s, by-id %s, by-path %s, '
        'formats YUYV' % (vga.bus_info, vga.by_id, vga.by_path))
    # Without a ROS graph: nothing else was printed, no node started.
    assert 'opened' not in node.output() and 'Traceback' not in node.output()


def test_auto_opens_the_first_usb_camera_not_the_boards_pipeline_node(
        launch, emulated_camera, ros_env):
    pipeline, webcam, vga = cameras(emulated_camera)
    node = launch('usbcam_publisher', params={'video_device': 'auto'},
                  env=env_of(ros_env, pipeline, webcam, vga))
    node.wait_for_output(r'opened auto \(/dev/video41\): 640x480', 30)
    wait_until(lambda: webcam.frames_served > 0, 20, what='frames from the USB camera')
    assert pipeline.frames_served == 0 and vga.frames_served == 0


def test_auto_follows_the_camera_to_its_new_node_after_a_replug(
        launch, emulated_camera, ros_env):
    pipeline, webcam, vga = cameras(emulated_camera)
    vga.unplug()
    node = launch('usbcam_publisher', params={'video_device': 'auto'},
                  env=env_of(ros_env, pipeline, webcam, vga))
    node.wait_for_output(r'opened auto \(/dev/video41\)', 30)
    wait_until(lambda: webcam.frames_served > 0, 20, what='frames before the unplug')
    webcam.unplug()
    webcam.replug(node=44)
    node.wait_for_output(r'is back', 30)
    assert re.search(r'opened auto \(/dev/video44\)', node.output()), node.output()
    served = webcam.frames_served
    wait_until(lambda: webcam.frames_served > served, 20, what='frames after the replug')


def test_auto_without_a_usb_camera_says_what_there_is(launch, emulated_camera, ros_env):
    pipeline = emulated_camera(model='pipeline_node', node=40)
    node = launch('usbcam_publisher', params={'video_device': 'auto'},
                  env=pipeline.env(ros_env))
    assert node.wait_exit(20) == 1
    assert re.search(r'cannot open video_device "auto": no USB camera \(driver uvcvideo\) is '
                     r'plugged in; the video devices here: /dev/video40 \(xilinx-vipp\)',
                     node.output()), node.output()
    assert 'Traceback' not in node.output()
