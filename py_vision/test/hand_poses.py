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
Hand landmark sets written by hand: a skeleton hand posed joint by joint, for the sign tests.

`pose(fingers, thumb)` builds a right hand seen with its palm to the camera, fingers up, in
hand sizes (wrist at the origin, middle knuckle one size above it; x right, y down, z towards
the viewer negative, as the landmark model gives them): each finger is bent at its three
joints by the angles given, in degrees, towards the camera. `place` then turns, scales, moves
and mirrors a set into a 640x480 picture. The proportions are an adult hand's, roughly.
"""

import math

import numpy as np

# The knuckles (x, y) of index, middle, ring and pinky, in hand sizes from the wrist; the
# thumb's base joint; the lengths of each finger's three bones and of the thumb's.
KNUCKLES = ((0.30, -0.95), (0.05, -1.0), (-0.18, -0.93), (-0.38, -0.82))
BONES = ((0.42, 0.25, 0.22), (0.47, 0.29, 0.24), (0.44, 0.27, 0.23), (0.33, 0.2, 0.2))
THUMB_CMC = (0.2, -0.15)
THUMB_BONES = (0.42, 0.32, 0.26)

# A finger's bends at its three joints, in degrees, towards the camera.
STRAIGHT = (0, 0, 0)
FOLDED = (85, 100, 60)
HALF = (45, 40, 20)

# The thumb: the direction (x, y, z) of each of its three bones, x towards the index side.
THUMB_OUT = ((0.77, -0.64, 0.0),) * 3  # spread out, 50 degrees from the fingers
THUMB_ACROSS = ((-0.1, -0.6, -0.8), (-0.7, -0.5, -0.5), (-0.9, -0.1, -0.3))  # over a fist
THUMB_ALONG = ((0.98, -0.19, 0.0),) * 3  # out along the knuckles' line (a thumbs-up)
THUMB_BESIDE = ((0.3, -0.95, -0.3),) * 3  # straight, against the index finger's side


def _finger(base, direction, bones, bends, towards):
    """Return the 4 joints from base: bones bent by `bends` degrees towards `towards`."""
    points = [np.asarray(base, np.float64)]
    angle = 0.0
    for bone, bend in zip(bones, bends):
        angle += math.radians(bend)
        step = direction * math.cos(angle) + towards * math.sin(angle)
        points.append(points[-1] + bone * step)
    return points


def pose(fingers=(STRAIGHT,) * 4, thumb=THUMB_OUT):
    """Return (21, 3) landmarks of a right hand, palm to the camera, fingers up."""
    up = np.array([0.0, -1.0, 0.0])
    camera = np.array([0.0, 0.0, -1.0])
    points = [np.zeros(3), np.array([THUMB_CMC[0], THUMB_CMC[1], 0.0])]
    for bone, direction in zip(THUMB_BONES, thumb):
        direction = np.asarray(direction, np.float64)
        points.append(points[-1] + bone * direction / np.linalg.norm(direction))
    for (x, y), bones, bends in zip(KNUCKLES, BONES, fingers):
        points += _finger((x, y, 0.0), up, bones, bends, camera)
    return np.array(points, np.float64)


def place(points, roll=0.0, size=100.0, at=(320.0, 240.0), mirror=False):
    """
    Return the set in picture pixels.

    Turned by `roll` degrees (clockwise on the screen), `size` pixels per hand size, the wrist
    at `at`; `mirror` flips the picture left to right (a right hand's becomes a left hand's).
    """
    points = np.array(points, np.float64)
    angle = math.radians(roll)
    cos, sin = math.cos(angle), math.sin(angle)
    x, y = points[:, 0].copy(), points[:, 1].copy()
    points[:, 0] = cos * x - sin * y
    points[:, 1] = sin * x + cos * y
    if mirror:  # the picture flipped about the wrist's vertical
        points[:, 0] = -points[:, 0]
    points *= size
    points[:, 0] += at[0]
    points[:, 1] += at[1]
    return points.astype(np.float32)


def thumb_up(down=False, **placing):
    """
    Return a thumbs-up (`down`: a thumbs-down).

    A fist with its thumb out along the knuckles' line, turned so that the thumb points
    straight up in the picture (straight down).
    """
    dx, dy = THUMB_ALONG[0][:2]
    roll = -90.0 - math.degrees(math.atan2(dy, dx)) + (180.0 if down else 0.0)
    return place(pose((FOLDED,) * 4, THUMB_ALONG), roll=roll, **placing)
