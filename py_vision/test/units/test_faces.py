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
FaceDetector on real photographs; the anchor decoding it shares with the palm detector.

The true face boxes were read off the pictures by eye (forehead to chin, cheek to cheek):
astronaut.png (512x512): x 180 to 268, y 78 to 175, her eyes at (203, 100) and (247, 105);
camera.png (512x512, the cameraman in profile): x 182 to 262, y 120 to 205.
"""

import math

import cv2
import numpy as np
import onnx_model
from photos import photo
from py_vision.capture.synthetic_picture import synthetic_frame
from py_vision.models.anchors import AnchorOptions, ssd_anchors
from py_vision.models.faces import Face, FaceDetector
from py_vision.models.runtime import load, ModelError
import pytest

ASTRONAUT_FACE = (180, 78, 88, 97)
ASTRONAUT_EYES = ((203, 100), (247, 105))
CAMERAMAN_FACE = (182, 120, 80, 85)


def box_iou(a, b):
    ax, ay, aw, ah = a
    bx, by, bw, bh = b
    w = max(0.0, min(ax + aw, bx + bw) - max(ax, bx))
    h = max(0.0, min(ay + ah, by + bh) - max(ay, by))
    return w * h / (aw * ah + bw * bh - w * h)


@pytest.fixture(scope='module')
def detector():
    return FaceDetector.from_file()


def only_face(faces):
    assert len(faces) == 1, ['%s %.2f' % (face.box.round(), face.score) for face in faces]
    face = faces[0]
    assert isinstance(face, Face)
    assert face.box.shape == (4,) and face.keypoints.shape == (6, 2)
    return face


def test_the_astronaut_has_one_face_where_it_is(detector):
    face = only_face(detector.detect(photo('astronaut.png')))
    assert face.score > 0.8
    assert box_iou(face.box, ASTRONAUT_FACE) > 0.7, face.box
    # Keypoints 0 and 1 are the person's right and left eye.
    for found, true in zip(face.keypoints[:2], ASTRONAUT_EYES):
        assert np.hypot(*(found - true)) < 10, face.keypoints[:2]


def test_the_cameraman_in_profile_is_found_too(detector):
    face = only_face(detector.detect(photo('camera.png')))
    assert face.score > 0.6
    assert box_iou(face.box, CAMERAMAN_FACE) > 0.6, face.box


def test_a_face_moved_and_scaled_in_a_vga_frame_is_found_there(detector):
    # The letterbox and its way back: the astronaut's 300x300 around her face, 1.5 times
    # larger, pasted at (150, 20) of a 640x480 frame.
    frame = np.full((480, 640, 3), 90, np.uint8)
    frame[20:470, 150:600] = cv2.resize(photo('astronaut.png')[30:330, 110:410], (450, 450),
                                        interpolation=cv2.INTER_LINEAR)
    face = only_face(detector.detect(frame))
    x, y, w, h = ASTRONAUT_FACE
    want = (150 + (x - 110) * 1.5, 20 + (y - 30) * 1.5, w * 1.5, h * 1.5)
    assert box_iou(face.box, want) > 0.7, (face.box, want)
    assert face.score > 0.8


@pytest.mark.parametrize('name', ['coffee.png', 'chelsea.png', 'rocket.jpg', 'coins.png',
                                  'horse.png'])
def test_photographs_without_faces_have_none(detector, name):
    # chelsea.png is a cat: a face, not a human one.
    assert detector.detect(photo(name)) == []


@pytest.mark.parametrize('value', [0, 128, 255])
def test_a_blank_frame_has_no_face(detector, value):
    assert detector.detect(np.full((480, 640, 3), value, np.uint8)) == []


def test_the_synthetic_camera_has_no_face(detector):
    assert detector.detect(synthetic_frame(0, 640, 480)) == []


def test_min_score_and_max_faces_are_kept(detector):
    picky = FaceDetector(detector.model, min_score=0.95)
    assert picky.detect(photo('astronaut.png')) == []
    # Two faces side by side: the astronaut's 240x240 around her face, and its mirror image.
    face = photo('astronaut.png')[10:250, 105:345]
    two = np.hstack([face, cv2.flip(face, 1)])
    found = detector.detect(two)
    assert len(found) == 2
    assert sorted(face.box[0] > 240 for face in found) == [False, True]
    assert len(FaceDetector(detector.model, max_faces=1).detect(two)) == 1


@pytest.mark.parametrize('image', [np.zeros((480, 640), np.uint8),
                                   np.zeros((480, 640, 3), np.float32),
                                   np.zeros((0, 640, 3), np.uint8)])
def test_not_a_bgr8_image_is_a_value_error(detector, image):
    with pytest.raises(ValueError, match=r'expected a bgr8 image \(height, width, 3\) uint8'):
        detector.detect(image)


def test_another_model_is_refused_by_name():
    with pytest.raises(ModelError, match='palm_detection_lite.tflite: not the model expected'):
        FaceDetector.from_file(
            FaceDetector.from_file().model.path.replace('face_detection_short_range',
                                                        'palm_detection_lite'))


@pytest.mark.parametrize('runtime, module', [('opencv', 'cv2'), ('onnxruntime', 'onnxruntime')])
def test_a_model_exported_again_with_its_outputs_in_another_order_is_read_by_name(
        tmp_path, runtime, module):
    # The face model's signature as ONNX, its scores listed before its regressors: one anchor
    # scores (logit 3), its box 24 input pixels square, its first keypoint (6, -4) from it.
    pytest.importorskip(module, reason='%s is not installed in this run' % runtime)
    anchors = ssd_anchors(AnchorOptions(128, 128, (8, 16, 16, 16)))
    index = 333
    regressors, scores = onnx_model.one_detection(anchors, 16, index, 24, (6, -4))
    path = onnx_model.write(tmp_path / 'face.onnx', onnx_model.constant_model_bytes(
        'input', (1, 128, 128, 3), [('classificators', scores), ('regressors', regressors)]))
    detector = FaceDetector(load(str(path), runtime=runtime))
    # A 256-pixel square frame is the 128-pixel input twice as large.
    face = only_face(detector.detect(np.zeros((256, 256, 3), np.uint8)))
    x, y = anchors[index, :2] * 256
    assert face.box == pytest.approx([x - 24, y - 24, 48, 48], abs=1e-3)
    assert face.keypoints[0] == pytest.approx([x + 12, y - 8], abs=1e-3)
    assert face.keypoints[1:] == pytest.approx(np.tile([x, y], (5, 1)), abs=1e-3)
    assert face.score == pytest.approx(1 / (1 + math.exp(-3)), rel=1e-5)
