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


"""The sign classifier on hand-written landmark sets (test/hand_poses.py), both hands."""

from hand_poses import FOLDED, HALF, place, pose, STRAIGHT, thumb_up
from hand_poses import THUMB_ACROSS, THUMB_BESIDE, THUMB_OUT
from hypothesis import given, settings, strategies as st
import numpy as np
from py_vision.models.signs import classify, SIGNS
import pytest

OPEN = pose((STRAIGHT,) * 4, THUMB_OUT)
FIST = pose((FOLDED,) * 4, THUMB_ACROSS)
FIST_THUMB_BESIDE = pose((FOLDED,) * 4, THUMB_BESIDE)
POINT = pose((STRAIGHT, FOLDED, FOLDED, FOLDED), THUMB_ACROSS)
POINT_THUMB_OUT = pose((STRAIGHT, FOLDED, FOLDED, FOLDED), THUMB_OUT)
AMBIGUOUS = {
    'two fingers out (a V)': pose((STRAIGHT, STRAIGHT, FOLDED, FOLDED), THUMB_ACROSS),
    'every finger half folded (a claw)': pose((HALF,) * 4, THUMB_OUT),
    'open hand, thumb against the index finger': pose((STRAIGHT,) * 4, THUMB_BESIDE),
    'fist with the thumb out sideways': pose((FOLDED,) * 4, THUMB_OUT),
    'index half folded, others folded': pose((HALF, FOLDED, FOLDED, FOLDED), THUMB_ACROSS),
}

rolls = st.floats(-180, 180)
sizes = st.floats(15, 400)
spots = st.tuples(st.floats(0, 640), st.floats(0, 480))


def both_hands(points, **placing):
    """Yield (landmarks, handedness, mirrored) for the right hand and its mirror image."""
    yield place(points, **placing), 'right', False
    yield place(points, mirror=True, **placing), 'left', True


def test_every_sign_has_a_landmark_set_here():
    made = {classify(place(OPEN), 'right'), classify(place(FIST), 'right'),
            classify(place(POINT, roll=90), 'right'), classify(place(POINT, roll=-90), 'right'),
            classify(thumb_up(), 'right'), classify(place(AMBIGUOUS['two fingers out (a V)']),
                                                    'right')}
    assert made == set(SIGNS)


@settings(deadline=None)  # not timed: the machine may be busy
@given(roll=rolls, size=sizes, at=spots)
def test_open_hand_at_any_roll_size_and_place_either_hand(roll, size, at):
    for landmarks, handedness, _ in both_hands(OPEN, roll=roll, size=size, at=at):
        assert classify(landmarks, handedness) == 'open_hand', (handedness, roll, size)


@settings(deadline=None)  # not timed: the machine may be busy
@given(roll=rolls, size=sizes, at=spots)
def test_fist_at_any_roll_size_and_place_either_hand(roll, size, at):
    for hand in (FIST, FIST_THUMB_BESIDE):
        for landmarks, handedness, _ in both_hands(hand, roll=roll, size=size, at=at):
            assert classify(landmarks, handedness) == 'fist', (handedness, roll, size)


@settings(deadline=None)  # not timed: the machine may be busy
@given(tilt=st.floats(-30, 30), size=sizes, at=spots)
def test_pointing_says_which_side_of_the_picture(tilt, size, at):
    # The index finger points up before the roll: +90 turns it to the picture's right.
    for hand in (POINT, POINT_THUMB_OUT):
        for landmarks, handedness, mirrored in both_hands(hand, roll=90 + tilt, size=size,
                                                          at=at):
            want = 'point_left' if mirrored else 'point_right'
            assert classify(landmarks, handedness) == want, (handedness, tilt)
        for landmarks, handedness, mirrored in both_hands(hand, roll=-90 + tilt, size=size,
                                                          at=at):
            want = 'point_right' if mirrored else 'point_left'
            assert classify(landmarks, handedness) == want, (handedness, tilt)


@pytest.mark.parametrize('roll', [0, 180, 45, -45, 135])
def test_pointing_up_down_or_diagonally_is_no_sign(roll):
    for landmarks, handedness, _ in both_hands(POINT, roll=roll):
        assert classify(landmarks, handedness) == 'unknown', (handedness, roll)


@settings(deadline=None)  # not timed: the machine may be busy
@given(tilt=st.floats(-30, 30), size=sizes, at=spots)
def test_thumb_up_either_hand_a_little_tilted(tilt, size, at):
    for mirror, handedness in ((False, 'right'), (True, 'left')):
        landmarks = thumb_up(size=size, at=at, mirror=mirror)
        # Tilt about the wrist: the thumb stays within 30 degrees of up.
        tilted = place(landmarks - landmarks[0], roll=tilt, size=1.0, at=at)
        assert classify(tilted, handedness) == 'thumb_up', (handedness, tilt)


@pytest.mark.parametrize('extra_roll', [180, 90, -90, 60, -60])
def test_thumb_down_or_sideways_is_no_sign(extra_roll):
    landmarks = thumb_up()
    turned = place(landmarks - landmarks[0], roll=extra_roll, size=1.0)
    assert classify(turned, 'right') == 'unknown'
    assert classify(thumb_up(down=True), 'right') == 'unknown'


@pytest.mark.parametrize('name', sorted(AMBIGUOUS))
@pytest.mark.parametrize('roll', [0, 90, -135])
def test_ambiguous_shapes_are_unknown(name, roll):
    for landmarks, handedness, _ in both_hands(AMBIGUOUS[name], roll=roll):
        assert classify(landmarks, handedness) == 'unknown', (name, handedness)


@settings(deadline=None)  # not timed: the machine may be busy
@given(roll=rolls, size=sizes)
def test_a_mirror_image_with_the_other_hand_gives_the_mirrored_sign(roll, size):
    swap = {'point_left': 'point_right', 'point_right': 'point_left'}
    for hand in (OPEN, FIST, POINT, POINT_THUMB_OUT) + tuple(AMBIGUOUS.values()):
        sign = classify(place(hand, roll=roll, size=size), 'right')
        mirrored = classify(place(hand, roll=roll, size=size, mirror=True), 'left')
        assert mirrored == swap.get(sign, sign), roll


def test_landmarks_without_z_work_alike():
    assert classify(place(OPEN)[:, :2], 'left') == 'open_hand'
    assert classify(place(POINT, roll=90)[:, :2], 'right') == 'point_right'


def test_a_collapsed_hand_is_unknown():
    assert classify(np.zeros((21, 3), np.float32), 'right') == 'unknown'


@pytest.mark.parametrize('landmarks, handedness, message', [
    (np.zeros((20, 3)), 'right', 'landmarks must be 21 finite points'),
    (np.zeros((21, 4)), 'right', 'landmarks must be 21 finite points'),
    (np.full((21, 3), np.nan), 'right', 'landmarks must be 21 finite points'),
    (place(OPEN), 'Right', "handedness must be 'left' or 'right'"),
    (place(OPEN), 'both', "handedness must be 'left' or 'right'"),
])
def test_bad_input_is_a_one_line_value_error(landmarks, handedness, message):
    with pytest.raises(ValueError, match=message) as raised:
        classify(landmarks, handedness)
    assert '\n' not in str(raised.value)
