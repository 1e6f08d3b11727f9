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
HandTracker: a real hand found with its fingertips where they are; no hand where there is none.

The real hand is OpenCV's documentation's photograph (Debian's opencv-doc, photos.hand_photo):
found as it is, mirrored and turned, its fingertips within TIP_TOLERANCE of where they are in
the picture, its sign an open hand, and followed from frame to frame. The hand region and the
crop it cuts are also checked geometrically (a marker drawn in a frame is found where the
crop's matrix says); the signs on landmark sets (test_signs).
"""

import math

import cv2
from hand_poses import FOLDED, place, pose, THUMB_ACROSS
from hypothesis import given, settings, strategies as st
import numpy as np
import onnx_model
from photos import hand_photo, photo
from py_vision.capture.synthetic_picture import synthetic_frame
from py_vision.models.anchors import AnchorOptions, ssd_anchors
from py_vision.models.crops import rotated_crop
from py_vision.models.hands import HAND_LANDMARKS, HandTracker, landmark_region
from py_vision.models.palm import hand_region, Palm, PalmDetector, upright_rotation
from py_vision.models.runtime import load, ModelError
from py_vision.models.signs import classify
import pytest

NO_HANDS = ['astronaut.png', 'coffee.png', 'chelsea.png', 'rocket.jpg', 'camera.png',
            'motorcycle_left.png', 'horse.png', 'coins.png']


@pytest.fixture(scope='module')
def tracker():
    return HandTracker.from_files()


# The fingertips' pads in the hand photograph (640x480: wrist at the left edge, thumb up,
# fingers to the right), read off the picture with a 40-pixel grid drawn on it, not from the
# model: thumb, index, middle, ring, little. Neighbouring tips are 60 pixels apart or more.
FINGERTIPS = ((248, 30), (475, 142), (528, 258), (505, 322), (420, 432))
TIP_INDICES = [4, 8, 12, 16, 20]
TIP_TOLERANCE = 30.0
TURNS = {'as it is': None, 'a quarter anticlockwise': cv2.ROTATE_90_COUNTERCLOCKWISE,
         'upside down': cv2.ROTATE_180, 'a quarter clockwise': cv2.ROTATE_90_CLOCKWISE}


def turned_point(point, turn, width=640, height=480):
    """Where a pixel of the photograph goes when the picture is turned with cv2.rotate."""
    x, y = point
    if turn is None:
        return x, y
    if turn == cv2.ROTATE_90_COUNTERCLOCKWISE:
        return y, width - 1 - x
    if turn == cv2.ROTATE_180:
        return width - 1 - x, height - 1 - y
    return height - 1 - y, x


def assert_tips(hand, expected):
    tips = hand.landmarks[TIP_INDICES, :2]
    misses = [(tuple(np.round(tip)), where) for tip, where in zip(tips, expected)
              if math.dist(tip, where) > TIP_TOLERANCE]
    assert not misses, 'fingertips (found, in the picture) farther than %g px: %s' % (
        TIP_TOLERANCE, misses)


@pytest.mark.parametrize('turn', list(TURNS))
def test_a_real_open_hand_is_found_with_its_fingertips_where_they_are(tracker, turn):
    image = hand_photo()
    if TURNS[turn] is not None:
        image = cv2.rotate(image, TURNS[turn])
    tracker.forget()
    hands = tracker.find(image)
    assert len(hands) == 1, hands
    hand = hands[0]
    # A hand's presence, not which hand it is: the model's left-or-right score for this palm
    # seen from above is close to even (0.3 to 0.65 as the picture turns), so either answer.
    assert hand.score > 0.9 and hand.handedness in ('left', 'right')
    assert_tips(hand, [turned_point(tip, TURNS[turn]) for tip in FINGERTIPS])
    assert classify(hand.landmarks, hand.handedness) == 'open_hand'


def test_the_hand_in_a_mirror_is_found_with_its_fingertips_mirrored(tracker):
    tracker.forget()
    hands = tracker.find(cv2.flip(hand_photo(), 1))
    assert len(hands) == 1, hands
    assert_tips(hands[0], [(639 - x, y) for x, y in FINGERTIPS])
    assert classify(hands[0].landmarks, hands[0].handedness) == 'open_hand'


def test_a_hand_moving_between_frames_is_followed_without_the_palm_detector(tracker):
    image = hand_photo()
    follows, palm, landmark = counted_tracker(tracker, max_hands=1)
    assert len(follows.find(image)) == 1 and palm.runs == 1
    # The hand 30 pixels to the left in the next frame: found where it went, by the landmark
    # model alone, in the region the last frame's landmarks gave.
    moved = cv2.warpAffine(image, np.float32([[1, 0, -30], [0, 1, 0]]), (640, 480),
                           borderMode=cv2.BORDER_REPLICATE)
    hands = follows.find(moved)
    assert len(hands) == 1 and (palm.runs, landmark.runs) == (1, 2)
    assert_tips(hands[0], [(x - 30, y) for x, y in FINGERTIPS])


@pytest.mark.parametrize('name', NO_HANDS)
def test_photographs_without_hands_have_none(tracker, name):
    assert tracker.find(photo(name)) == []


def test_the_presence_score_turns_down_what_the_palm_detector_mistakes(tracker):
    # The palm detector alone finds a "palm" in these photographs (a horse's leg, cells under
    # a microscope); the landmark model's presence score is what says there is no hand.
    for name in ('cell.png', 'horse.png'):
        assert tracker.palms.detect(photo(name)), name
        assert tracker.find(photo(name)) == [], name
    permissive = HandTracker(tracker.palms.model, tracker.landmark_model, min_hand_score=0.0)
    found = permissive.find(photo('horse.png'))
    assert found, 'with no presence threshold the mistaken palm becomes a hand'
    hand = found[0]
    assert hand.landmarks.shape == (21, 3) and hand.landmarks.dtype == np.float32
    assert hand.handedness in ('left', 'right') and 0 <= hand.score < 0.5


@pytest.mark.parametrize('index', [0, 7, 45])
def test_the_synthetic_camera_has_no_hand(tracker, index):
    assert tracker.find(synthetic_frame(index, 640, 480)) == []


@pytest.mark.parametrize('value', [0, 255])
def test_a_blank_frame_has_no_hand(tracker, value):
    assert tracker.find(np.full((480, 640, 3), value, np.uint8)) == []


def test_the_mirror_setting_swaps_the_hand_it_reports(tracker):
    frame = photo('horse.png')
    plain = HandTracker(tracker.palms.model, tracker.landmark_model, min_hand_score=0.0)
    mirrored = HandTracker(tracker.palms.model, tracker.landmark_model, min_hand_score=0.0,
                           mirrored=True)
    assert {plain.find(frame)[0].handedness, mirrored.find(frame)[0].handedness} == {
        'left', 'right'}


def test_the_landmark_names():
    assert len(HAND_LANDMARKS) == 21
    assert HAND_LANDMARKS[0] == 'wrist' and HAND_LANDMARKS[8] == 'index_tip'


def palm(wrist, knuckle, box=(100.0, 200.0, 40.0, 40.0)):
    keypoints = np.zeros((7, 2), np.float32)
    keypoints[0], keypoints[2] = wrist, knuckle
    return Palm(np.array(box, np.float32), 0.9, keypoints)


def test_an_upright_palm_gives_an_upright_region_above_it():
    region = hand_region(palm((120, 235), (120, 205)))
    assert region.rotation == pytest.approx(0.0)
    # Half the palm's height towards the fingers (up), 2.6 times its side.
    assert (region.x, region.y) == pytest.approx((120.0, 200.0))
    assert region.side == pytest.approx(104.0)


@pytest.mark.parametrize('direction, rotation, shift', [
    ((1, 0), math.pi / 2, (20, 0)),  # fingers to the right: turned a quarter clockwise
    ((-1, 0), -math.pi / 2, (-20, 0)),
    ((0, 1), math.pi, (0, 20)),  # fingers down
])
def test_a_turned_palm_gives_a_region_turned_and_moved_to_its_fingers(
        direction, rotation, shift):
    wrist = np.array([120.0, 220.0])
    region = hand_region(palm(wrist, wrist + 30 * np.array(direction)))
    assert abs(math.remainder(region.rotation - rotation, 2 * math.pi)) < 1e-6
    assert (region.x - 120, region.y - 220) == pytest.approx(shift, abs=1e-4)


def test_upright_rotation_is_within_a_half_turn():
    for angle in np.linspace(-3 * math.pi, 3 * math.pi, 37):
        end = np.array([math.cos(angle), -math.sin(angle)])
        assert -math.pi <= upright_rotation(np.zeros(2), end) <= math.pi


@pytest.mark.parametrize('rotation', [0.0, 0.6, math.pi / 2, -2.5])
def test_the_crop_and_its_matrix_agree_on_where_a_marker_is(rotation):
    # A red dot 30 px from the region's centre, towards its "up" (the turned -y): the crop
    # shows it straight above its centre, and the matrix maps it back onto the dot.
    frame = np.zeros((480, 640, 3), np.uint8)
    center = np.array([300.0, 220.0])
    up = np.array([math.sin(rotation), -math.cos(rotation)])
    dot = center + 30 * up
    cv2.circle(frame, (int(round(dot[0])), int(round(dot[1]))), 4, (0, 0, 255), -1)
    crop = rotated_crop(frame, tuple(center), 120.0, rotation, 224, (0.0, 1.0))
    assert crop.tensor.shape == (1, 224, 224, 3) and crop.tensor.dtype == np.float32
    red = crop.tensor[0, :, :, 0]  # RGB now
    ys, xs = np.nonzero(red > 0.5)
    seen = np.array([xs.mean(), ys.mean()])
    assert seen == pytest.approx([112, 112 - 30 * 224 / 120], abs=1.5)
    assert crop.points_to_image(seen) == pytest.approx(dot, abs=1.0)


@settings(deadline=None)  # not timed: the machine may be busy
@given(roll=st.floats(-180, 180), size=st.floats(20, 300), x=st.floats(0, 640),
       y=st.floats(0, 480))
def test_the_region_from_landmarks_is_turned_with_the_hand_and_holds_all_of_it(roll, size, x,
                                                                               y):
    for hand in (pose(), pose((FOLDED,) * 4, THUMB_ACROSS)):
        landmarks = place(hand, roll=roll, size=size, at=(x, y))
        region = landmark_region(landmarks)
        # The posed hand's knuckles lean 3 degrees right of its wrist's vertical.
        turn = math.degrees(math.remainder(region.rotation - math.radians(roll + 3.2),
                                           2 * math.pi))
        assert abs(turn) < 1.0, (region.rotation, roll)
        # Every landmark inside the square, in the square's own (turned) axes.
        cos, sin = math.cos(region.rotation), math.sin(region.rotation)
        relative = landmarks[:, :2] - (region.x, region.y)
        along = np.abs(relative @ np.array([[cos, -sin], [sin, cos]]))
        assert along.max() < region.side / 2, (roll, size)
        assert region.side < 5 * size  # and not much more than the hand


class Counted:
    """A model that counts its runs (the tracker's wiring, seen from the models)."""

    def __init__(self, model):
        self.model, self.runs = model, 0
        self.path, self.runtime, self.threads = model.path, model.runtime, model.threads
        self.inputs, self.outputs = model.inputs, model.outputs

    def run(self, *arrays):
        self.runs += 1
        return self.model.run(*arrays)


def counted_tracker(tracker, **options):
    palm, landmark = Counted(tracker.palms.model), Counted(tracker.landmark_model)
    return HandTracker(palm, landmark, **options), palm, landmark


def test_a_tracked_hand_skips_the_palm_detector_until_it_is_lost(tracker):
    # With no thresholds the landmark model's answer on the synthetic frame is "a hand":
    # the tracker then follows it with one landmark pass per frame.
    frame = synthetic_frame(0, 640, 480)
    follows, palm, landmark = counted_tracker(tracker, min_palm_score=0.0, min_hand_score=0.0,
                                              max_hands=1)
    assert len(follows.find(frame)) == 1 and (palm.runs, landmark.runs) == (1, 1)
    assert len(follows.find(frame)) == 1 and (palm.runs, landmark.runs) == (1, 2)
    follows.forget()
    assert len(follows.find(frame)) == 1 and (palm.runs, landmark.runs) == (2, 3)
    # Without tracking, or while fewer hands than max_hands are tracked: the palm detector.
    fresh, palm, landmark = counted_tracker(tracker, min_palm_score=0.0, min_hand_score=0.0,
                                            max_hands=1, track=False)
    fresh.find(frame)
    fresh.find(frame)
    assert (palm.runs, landmark.runs) == (2, 2)
    # A hand that is gone (its presence now below the threshold) is dropped, and the next
    # frame is searched with the palm detector again.
    follows, palm, landmark = counted_tracker(tracker, min_palm_score=0.0, min_hand_score=0.0,
                                              max_hands=1)
    assert len(follows.find(frame)) == 1 and (palm.runs, landmark.runs) == (1, 1)
    follows.min_hand_score = 0.5
    assert follows.find(frame) == [] and (palm.runs, landmark.runs) == (1, 2)
    assert follows.find(frame) == [] and (palm.runs, landmark.runs) == (2, 3)


def test_other_models_are_refused_by_name(tracker):
    face = tracker.palms.model.path.replace('palm_detection_lite',
                                            'face_detection_short_range')
    with pytest.raises(ModelError, match='face_detection_short_range.tflite: not the model'):
        HandTracker.from_files(palm_path=face)
    with pytest.raises(ModelError, match='face_detection_short_range.tflite: not the model'):
        HandTracker.from_files(landmark_path=face)


ONNX_RUNTIMES = [('opencv', 'cv2'), ('onnxruntime', 'onnxruntime')]


@pytest.mark.parametrize('runtime, module', ONNX_RUNTIMES)
def test_a_landmark_model_exported_again_with_its_outputs_in_another_order_reads_the_same(
        tracker, tmp_path, runtime, module):
    # hand_landmark_lite's signature as ONNX, its outputs listed in another order: the world
    # landmarks first, handedness before presence. Presence and handedness have the same shape:
    # read by position, the left-hand score 0.2 would be taken for the presence (no hand).
    pytest.importorskip(module, reason='%s is not installed in this run' % runtime)
    angles = np.linspace(0, 2 * math.pi, 21, endpoint=False)
    points = np.stack([112 + 50 * np.cos(angles), 112 + 50 * np.sin(angles), np.zeros(21)], 1)
    outputs = [('Identity_3', np.full((1, 63), 0.01)), ('Identity_2', [[0.2]]),
               ('Identity_1', [[0.9]]), ('Identity', points.reshape(1, 63))]
    path = onnx_model.write(tmp_path / 'landmarks.onnx', onnx_model.constant_model_bytes(
        'input_1', (1, 224, 224, 3), outputs))
    exported = HandTracker(tracker.palms.model, load(str(path), runtime=runtime), max_hands=1,
                           track=False)
    image = hand_photo()
    hands = exported.find(image)
    assert len(hands) == 1, 'the presence score was not read as the presence'
    hand = hands[0]
    # The model sees no left hand (0.2): in an unmirrored picture, the person's left hand.
    assert hand.score == pytest.approx(0.9) and hand.handedness == 'left'
    # The landmarks circle the hand region's centre, 50/224 of its side away (the world
    # landmarks, 0.01 pixels in the crop, would all sit at its corner).
    region = hand_region(tracker.palms.detect(image)[0])
    offsets = hand.landmarks[:, :2] - (region.x, region.y)
    assert offsets.mean(axis=0) == pytest.approx([0, 0], abs=1e-2)
    assert np.hypot(*offsets.T) == pytest.approx(np.full(21, 50 * region.side / 224), rel=1e-4)


@pytest.mark.parametrize('runtime, module', ONNX_RUNTIMES)
def test_a_palm_model_exported_again_with_its_outputs_in_another_order_is_read_by_name(
        tmp_path, runtime, module):
    pytest.importorskip(module, reason='%s is not installed in this run' % runtime)
    anchors = ssd_anchors(AnchorOptions(192, 192, (8, 16, 16, 16)))
    index = 1500
    regressors, scores = onnx_model.one_detection(anchors, 18, index, 30, (0, 10))
    path = onnx_model.write(tmp_path / 'palm.onnx', onnx_model.constant_model_bytes(
        'input_1', (1, 192, 192, 3), [('Identity_1', scores), ('Identity', regressors)]))
    palms = PalmDetector(load(str(path), runtime=runtime)).detect(np.zeros((192, 192, 3),
                                                                           np.uint8))
    assert len(palms) == 1
    x, y = anchors[index, :2] * 192
    assert palms[0].box == pytest.approx([x - 15, y - 15, 30, 30], abs=1e-3)
    assert palms[0].keypoints[0] == pytest.approx([x, y + 10], abs=1e-3)
