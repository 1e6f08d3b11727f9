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
A handful of hand signs from a hand's 21 landmarks: not sign language, a few robot commands.

`classify(landmarks, handedness)` returns one of SIGNS:

- 'open_hand': all five fingers stretched out (a "stop" palm, or the back of the hand), at any
  roll: fingers up, sideways or down alike;
- 'fist': the four fingers folded into the palm and the thumb not sticking out, at any roll;
- 'point_left' and 'point_right': only the index finger stretched out (the thumb may be out
  too), pointing to the left or the right of the picture, within 35 degrees of horizontal.
  These are the picture's left and right: facing a camera that does not mirror, pointing to
  your own left shows as 'point_right';
- 'thumb_up': the four fingers folded and the thumb stretched out, pointing up in the picture
  within 35 degrees (a thumb down is not a sign);
- 'unknown': anything else: two fingers out, fingers half folded, a pointing finger that
  points up or at the camera, a hand seen edge-on.

How: the hand's size is the wrist to middle knuckle distance, so nothing depends on how big
the hand is in the picture. A finger is stretched when its joints are nearly in line (its
three joints, knuckle included, bend less than 60 degrees together) and its tip is farther
from the wrist than its middle joint; it is folded when its tip is nearer the wrist than its
middle joint. The thumb is out when it bends less than 40 degrees at each joint and its tip
is more than half a hand size from every joint of the index and middle fingers (a thumb held
against the index finger is not out). Angles and distances use x, y and the model's relative
z, so fingers folded towards the camera read as folded. The two hands are alike here: a left
and a right hand making the same shape get the same sign (handedness is checked; a step may
map the signs per hand).

Limits: this is geometry on landmarks, tested on hand-written landmark sets, not a trained
classifier. The landmark model guesses fingers it cannot see (a fist seen from the side,
fingers behind the palm), so make the signs facing the camera; a finger that is neither
stretched nor folded gives 'unknown' rather than a guess; a relaxed open hand whose thumb
rests against the index finger is 'unknown' (spread the thumb).
"""

import math
from typing import Optional, Sequence

import numpy as np

__all__ = ['classify', 'SIGNS']

SIGNS = ('open_hand', 'fist', 'point_left', 'point_right', 'thumb_up', 'unknown')

HANDEDNESS = ('left', 'right')

_WRIST = 0
_THUMB = (1, 2, 3, 4)
_FINGERS = ((5, 6, 7, 8), (9, 10, 11, 12), (13, 14, 15, 16), (17, 18, 19, 20))
_MIDDLE_MCP = 9
_NEAR_THUMB = list(range(5, 13))  # the index and middle fingers' joints

_FINGER_STRAIGHT = math.radians(60)  # the most a stretched finger bends, its 3 joints together
_THUMB_STRAIGHT = math.radians(40)  # the most a stretched thumb bends at each joint
_THUMB_OUT = 0.5  # hand sizes from the thumb tip to the index and middle fingers
_DIRECTION = math.radians(35)  # how far from exact a pointing direction may be

STRETCHED, FOLDED = 'stretched', 'folded'


def _bend(a: Sequence[float], b: Sequence[float], c: Sequence[float]) -> float:
    """Return the angle at b between a -> b and b -> c: 0 when a, b, c are in line."""
    first = [q - p for p, q in zip(a, b)]
    second = [q - p for p, q in zip(b, c)]
    norms = math.hypot(*first) * math.hypot(*second)
    if norms == 0:
        return math.pi
    cosine = sum(x * y for x, y in zip(first, second)) / norms
    return math.acos(max(-1.0, min(1.0, cosine)))


def finger_state(points: Sequence[Sequence[float]], joints) -> Optional[str]:
    """Return STRETCHED, FOLDED or None (neither) for a finger's (mcp, pip, dip, tip)."""
    mcp, pip, dip, tip = (points[index] for index in joints)
    wrist = points[_WRIST]
    tip_reach = math.dist(tip, wrist)
    pip_reach = math.dist(pip, wrist)
    if tip_reach < pip_reach:
        return FOLDED
    bends = _bend(wrist, mcp, pip) + _bend(mcp, pip, dip) + _bend(pip, dip, tip)
    if bends < _FINGER_STRAIGHT and tip_reach > pip_reach:
        return STRETCHED
    return None


def thumb_out(points: Sequence[Sequence[float]], size: float) -> bool:
    """Return whether the thumb sticks out: nearly straight, its tip away from the fingers."""
    cmc, mcp, ip, tip = (points[index] for index in _THUMB)
    straight = max(_bend(mcp, ip, tip), _bend(cmc, mcp, tip)) < _THUMB_STRAIGHT
    nearest = min(math.dist(points[index], tip) for index in _NEAR_THUMB)
    return straight and nearest > _THUMB_OUT * size


def _direction(start: Sequence[float], end: Sequence[float]) -> Optional[str]:
    """Return 'left', 'right', 'up' or 'down' in the picture, or None (between, or edge-on)."""
    dx, dy = end[0] - start[0], end[1] - start[1]
    length = math.hypot(dx, dy)
    if length == 0 or length < 0.5 * math.dist(end, start):
        return None  # mostly towards or away from the camera
    for name, (ux, uy) in (('right', (1, 0)), ('left', (-1, 0)), ('up', (0, -1)),
                           ('down', (0, 1))):
        if math.acos(max(-1.0, min(1.0, (dx * ux + dy * uy) / length))) <= _DIRECTION:
            return name
    return None


def classify(landmarks: np.ndarray, handedness: str) -> str:
    """
    Return the sign (one of SIGNS) that a hand's landmarks make.

    landmarks: (21, 3) (or (21, 2)) x, y in picture pixels (y down) and z, in
    hands.HAND_LANDMARKS' order; handedness: 'left' or 'right'. Raises ValueError on others.
    """
    points = np.asarray(landmarks, dtype=np.float64)
    if points.ndim != 2 or points.shape[0] != 21 or points.shape[1] not in (2, 3) \
            or not np.all(np.isfinite(points)):
        raise ValueError('landmarks must be 21 finite points (21, 3), got shape %s'
                         % (points.shape,))
    if handedness not in HANDEDNESS:
        raise ValueError("handedness must be 'left' or 'right', not %r" % (handedness,))
    # 21 points of plain floats: a few dozen small computations cost less in Python's math
    # than as many numpy calls.
    points = points.tolist()
    size = math.dist(points[_MIDDLE_MCP], points[_WRIST])
    if size == 0:
        return 'unknown'
    states = [finger_state(points, joints) for joints in _FINGERS]
    thumb = thumb_out(points, size)
    if all(state == STRETCHED for state in states):
        return 'open_hand' if thumb else 'unknown'
    if all(state == FOLDED for state in states):
        if not thumb:
            return 'fist'
        return 'thumb_up' if _direction(points[_THUMB[1]], points[_THUMB[3]]) == 'up' \
            else 'unknown'
    if states[0] == STRETCHED and all(state == FOLDED for state in states[1:]):
        direction = _direction(points[_FINGERS[0][0]], points[_FINGERS[0][3]])
        if direction in ('left', 'right'):
            return 'point_' + direction
    return 'unknown'
