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
The built-in model steps in the installed vision_step: hand_signs and faces.

hand_signs on the synthetic camera (no hand in it): every Twist all zero and `hand_sign` saying
so, seen by a subscriber of its own; on a real photograph of an open hand (photos.hand_photo):
`open_hand`, the turtle told to stand still, the hand drawn; its statistics line and
/diagnostics splitting a frame's processing time into its models' and the rest. faces on a
real photograph
(scikit-image's astronaut): the face where it is, in vision_msgs where installed, else in the
JSON fallback.
"""

import json
import re
import signal

from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import Twist
import numpy as np
import photos
from rclpy.qos import QoSProfile, ReliabilityPolicy
from ros_harness import status_values, wait_until
from sensor_msgs.msg import Image
from std_msgs.msg import String

# The .tflite runtime and its version: LiteRT on a PC, tflite_runtime in the board-version run.
RUNTIME = r'(LiteRT|tflite_runtime) \d+\.\d+'
RELIABLE = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)
CAMERA = {'video_device': 'synthetic', 'image_width': 320, 'image_height': 240,
          'framerate': 10.0}
# Where the astronaut's face is in skimage's astronaut.png (512x512), read off the picture
# with a grid drawn on it: cheek to cheek x 180..265, brow to chin y 75..175; the box's centre
# and side, in pixels, within TOLERANCE (the detector's box is square and a little larger).
FACE_CENTER, FACE_SIZE, TOLERANCE = (225.0, 128.0), 95.0, 25.0


def twist_values(msg):
    return (msg.linear.x, msg.linear.y, msg.linear.z,
            msg.angular.x, msg.angular.y, msg.angular.z)


def test_hand_signs_on_a_camera_without_hands_stands_still(launch, peer):
    twists = peer.collect(Twist, '/turtle1/cmd_vel', RELIABLE)
    signs = peer.collect(String, 'hand_sign', RELIABLE)
    images = peer.collect(Image, 'vision_step/image', RELIABLE)
    node = launch('vision_step', params={'step': 'hand_signs', 'linear_speed': 2.0})
    line = node.wait_for_output(r'running step hand_signs .*', timeout=60.0).group(0)
    assert re.search(RUNTIME, line), line
    for words in ('palm_detection_lite.tflite', 'hand_landmark_lite.tflite',
                  'Twist on /turtle1/cmd_vel', 'signs on /hand_sign'):
        assert words in line, line
    launch('usbcam_publisher', params=CAMERA)
    wait_until(lambda: len(twists) >= 5 and len(signs) >= 5 and images, 60.0, interval=0.1,
               what='five Twists, five signs and an image')
    assert all(twist_values(msg) == (0.0,) * 6 for msg in list(twists)), list(twists)
    assert {msg.data for msg in list(signs)} == {'no_hand'}
    assert images[0].encoding == 'bgr8' and (images[0].width, images[0].height) == (320, 240)
    assert node.stop(signal.SIGINT) == 0
    assert 'Traceback' not in node.output()


def photo_message(image, frame_id):
    msg = Image(height=image.shape[0], width=image.shape[1], encoding='bgr8',
                step=image.shape[1] * 3, data=image.tobytes())
    msg.header.frame_id = frame_id
    return msg


def test_hand_signs_sees_the_open_hand_in_a_photograph(launch, peer):
    hand = photos.hand_photo()
    signs = peer.collect(String, 'hand_sign', RELIABLE)
    twists = peer.collect(Twist, '/turtle1/cmd_vel', RELIABLE)
    images = peer.collect(Image, 'vision_step/image', RELIABLE)
    node = launch('vision_step', params={'step': 'hand_signs'})
    node.wait_for_output(r'running step hand_signs', timeout=60.0)
    publisher = peer.node.create_publisher(Image, 'usb_camera/image', RELIABLE)
    msg = photo_message(hand, 'hand')

    def answered():
        msg.header.stamp.sec += 1
        publisher.publish(msg)
        return signs and images and twists
    wait_until(answered, 30.0, interval=0.5, what='the sign of the photographed hand')
    assert signs[0].data == 'open_hand', [s.data for s in list(signs)]
    assert twist_values(twists[0]) == (0.0,) * 6  # an open hand: stand still
    # The landmarks are drawn over the hand: many pixels differ from the photograph.
    drawn = np.frombuffer(bytes(images[0].data), np.uint8).reshape(hand.shape)
    assert images[0].header.frame_id == 'hand'
    assert (drawn != hand).any(axis=2).sum() > 2000
    assert node.stop(signal.SIGINT) == 0
    assert 'Traceback' not in node.output()


# The statistics line's processing time and its split: (processing p50, models p50, rest p50).
SPLIT_LINE = re.compile(r'processing p50 ([\d.]+) ms p99 [\d.]+ ms '
                        r'\(p50: models ([\d.]+) ms, rest ([\d.]+) ms\)')


def test_hand_signs_splits_its_processing_time_into_the_models_and_the_rest(launch, peer):
    arrays = peer.collect(DiagnosticArray, '/diagnostics', RELIABLE)
    node = launch('vision_step', params={'step': 'hand_signs'})
    node.wait_for_output(r'running step hand_signs', timeout=60.0)
    publisher = peer.node.create_publisher(Image, 'usb_camera/image', RELIABLE)
    msg = photo_message(photos.hand_photo(), 'hand')

    def sent_and(found):
        def check():
            msg.header.stamp.sec += 1
            publisher.publish(msg)
            return found()
        return check

    def split_reported():
        values = status_values(arrays, 'vision_step: processing')
        return values if values.get('models p50 ms') not in (None, '', '0.0') else None
    values = wait_until(sent_and(split_reported), 30.0, interval=0.5,
                        what='/diagnostics with the models time of a frame')
    processing, models, rest = (float(values[key]) for key in (
        'processing p50 ms', 'models p50 ms', 'rest p50 ms'))
    # The palm detector and the landmark model ran in each frame: part of its time, not more.
    assert 0 < models <= processing, values
    assert 0 <= rest <= processing, values
    assert float(values['models p99 ms']) <= float(values['processing p99 ms']), values
    assert int(values['frames running models']) >= 1, values
    # Since start, the worker's CPU time in processing, and of it in models.
    assert 0 < int(values['models CPU ms']) <= int(values['processing CPU ms']), values
    line = wait_until(sent_and(lambda: SPLIT_LINE.search(node.output())), 30.0, interval=0.5,
                      what='the statistics line with the split:\n%s' % node.output())
    assert 0 < float(line.group(2)) <= float(line.group(1)), line.group(0)
    assert node.stop(signal.SIGINT) == 0
    assert 'Traceback' not in node.output()


def vision_msgs_installed():
    try:
        import vision_msgs.msg  # noqa: F401
    except ImportError:
        # The board-version run (scripts/test.sh) is the boards' image, which has vision-msgs:
        # there the JSON fallback would be a path no board takes.
        import os
        if os.environ.get('PY_VISION_BOARD_RUN') == '1':
            raise
        return False
    return True


def boxes_from_detection_array(msg):
    out = []
    for detection in msg.detections:
        center = getattr(detection.bbox.center, 'position', detection.bbox.center)
        out.append((center.x, center.y, detection.bbox.size_x, detection.bbox.size_y,
                    detection.results[0].hypothesis.score))
    return out


def boxes_from_json(msg):
    data = json.loads(msg.data)
    return data['header'], [(d['bbox']['center_x'], d['bbox']['center_y'], d['bbox']['size_x'],
                             d['bbox']['size_y'], d['score']) for d in data['detections']]


def test_faces_finds_the_astronauts_face_and_publishes_it_with_the_frames_header(launch, peer):
    if vision_msgs_installed():
        from vision_msgs.msg import Detection2DArray
        received = peer.collect(Detection2DArray, 'detections', RELIABLE)
    else:
        received = peer.collect(String, 'detections_json', RELIABLE)
    images = peer.collect(Image, 'vision_step/image', RELIABLE)
    node = launch('vision_step', params={'step': 'faces'})
    line = node.wait_for_output(r'running step faces .*', timeout=60.0).group(0)
    assert re.search(RUNTIME, line), line
    assert 'face_detection_short_range.tflite' in line, line
    if not vision_msgs_installed():
        assert ('vision_msgs is not installed: detections as JSON (std_msgs/String) on '
                '/detections_json') in line, line
    publisher = peer.node.create_publisher(Image, 'usb_camera/image', RELIABLE)
    photo = photos.photo('astronaut.png')
    msg = photo_message(photo, 'photo')

    def answered():
        msg.header.stamp.sec += 1
        publisher.publish(msg)
        return received and images
    wait_until(answered, 30.0, interval=0.5, what='detections of the photograph')
    first = received[0]
    if vision_msgs_installed():
        header, boxes = first.header, boxes_from_detection_array(first)
        assert header.frame_id == 'photo' and header.stamp.sec >= 1
    else:
        header, boxes = boxes_from_json(first)
        assert header['frame_id'] == 'photo' and header['stamp']['sec'] >= 1
    assert len(boxes) == 1, boxes
    x, y, width, height, score = boxes[0]
    assert abs(x - FACE_CENTER[0]) < TOLERANCE and abs(y - FACE_CENTER[1]) < TOLERANCE, boxes
    assert abs(width - FACE_SIZE) < TOLERANCE and abs(height - FACE_SIZE) < TOLERANCE, boxes
    assert score > 0.5
    # The box is drawn on the published image, the rest is the photograph.
    drawn = np.frombuffer(bytes(images[0].data), np.uint8).reshape(photo.shape)
    assert (drawn != photo).any(axis=2).sum() > 4 * FACE_SIZE
    assert (drawn[300:, :] == photo[300:, :]).all()
    assert node.stop(signal.SIGINT) == 0
    assert 'Traceback' not in node.output()
