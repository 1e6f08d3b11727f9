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


"""SSD anchors, decoding and weighted non-maximum suppression, on numbers worked out by hand."""

import warnings

import numpy as np
from py_vision.models.anchors import (AnchorOptions, decode, DecodeOptions, Detections, iou,
                                      ssd_anchors, weighted_nms)
import pytest

PALM = AnchorOptions(192, 192, (8, 16, 16, 16))
FACE = AnchorOptions(128, 128, (8, 16, 16, 16))


def test_palm_anchors_grid():
    anchors = ssd_anchors(PALM)
    # 24x24 cells with 2 anchors (stride 8), then 12x12 cells with 6 (three stride-16 layers).
    assert anchors.shape == (24 * 24 * 2 + 12 * 12 * 6, 4) == (2016, 4)
    assert anchors[0] == pytest.approx([0.5 / 24, 0.5 / 24, 1, 1])
    assert anchors[1] == pytest.approx(anchors[0])
    assert anchors[2] == pytest.approx([1.5 / 24, 0.5 / 24, 1, 1])  # x first, then y
    assert anchors[2 * 24] == pytest.approx([0.5 / 24, 1.5 / 24, 1, 1])
    assert anchors[1152] == pytest.approx([0.5 / 12, 0.5 / 12, 1, 1])
    assert np.all(anchors[1152:1158] == anchors[1152])
    assert anchors[-1] == pytest.approx([11.5 / 12, 11.5 / 12, 1, 1])


def test_face_anchors_grid():
    anchors = ssd_anchors(FACE)
    assert anchors.shape == (16 * 16 * 2 + 8 * 8 * 6, 4) == (896, 4)
    assert anchors[512] == pytest.approx([0.5 / 8, 0.5 / 8, 1, 1])


def test_anchors_of_varying_size():
    options = AnchorOptions(64, 64, (32, 64), aspect_ratios=(1.0, 2.0),
                            fixed_anchor_size=False)
    anchors = ssd_anchors(options)
    # Per cell: one anchor per aspect ratio and one interpolated; 2x2 + 1x1 cells.
    assert anchors.shape == (4 * 3 + 1 * 3, 4)
    scale = options.min_scale
    assert anchors[0, 2:] == pytest.approx([scale, scale])
    assert anchors[1, 2:] == pytest.approx([scale * 2 ** 0.5, scale / 2 ** 0.5])
    interpolated = (scale * options.max_scale) ** 0.5
    assert anchors[2, 2:] == pytest.approx([interpolated, interpolated])


def face_output(anchor, raw, logit, others=-20.0):
    regressors = np.zeros((1, 896, 16), np.float32)
    scores = np.full((1, 896, 1), others, np.float32)
    regressors[0, anchor] = raw
    scores[0, anchor] = logit
    return regressors, scores


def test_decode_puts_the_box_and_keypoints_at_the_anchor_plus_offsets():
    anchors = ssd_anchors(FACE)
    options = DecodeOptions(6, 128, 128, 128, 128, min_score=0.5)
    raw = np.zeros(16, np.float32)
    raw[:4] = (12.8, -6.4, 25.6, 38.4)  # x, y offsets and w, h in input pixels
    raw[4:6] = (1.28, 2.56)  # keypoint 0
    found = decode(*face_output(700, raw, 2.0), anchors, options)
    assert len(found) == 1
    cx, cy = anchors[700, 0] + 0.1, anchors[700, 1] - 0.05
    assert found.boxes[0] == pytest.approx([cx - 0.1, cy - 0.15, cx + 0.1, cy + 0.15], abs=1e-6)
    assert found.keypoints[0, 0] == pytest.approx(anchors[700, :2] + [0.01, 0.02], abs=1e-6)
    assert found.keypoints[0, 1] == pytest.approx(anchors[700, :2], abs=1e-6)
    assert found.scores[0] == pytest.approx(1 / (1 + np.exp(-2.0)))


def test_decode_keeps_only_scores_over_the_threshold_and_clips_huge_logits():
    anchors = ssd_anchors(FACE)
    raw = np.zeros(16, np.float32)
    with warnings.catch_warnings():
        warnings.simplefilter('error')  # no overflow in the sigmoid
        found = decode(*face_output(3, raw, 1e30, others=-1e30), anchors,
                       DecodeOptions(6, 128, 128, 128, 128, min_score=0.5))
    assert len(found) == 1 and found.scores[0] == pytest.approx(1.0)
    nothing = decode(*face_output(3, raw, 0.0), anchors,
                     DecodeOptions(6, 128, 128, 128, 128, min_score=0.51))
    assert len(nothing) == 0 and nothing.keypoints.shape == (0, 6, 2)


def sigmoid_keeps(raw_scores, options):
    """Return the anchors decode keeps, as the sigmoid of every clipped logit says."""
    logits = np.clip(raw_scores.reshape(-1), -options.score_clipping, options.score_clipping)
    return np.flatnonzero(1.0 / (1.0 + np.exp(-logits.astype(np.float64))) >= options.min_score)


def test_decode_finds_what_the_sigmoid_of_every_anchor_finds_near_the_threshold():
    # decode() skips the sigmoids when the best logit is well below the threshold's: the
    # same anchors either way, also with the best anchor a hair from the threshold.
    anchors = ssd_anchors(FACE)
    rng = np.random.default_rng(44)
    regressors = rng.normal(0, 5, (1, 896, 16)).astype(np.float32)
    skipped = 0
    for trial in range(3000):
        min_score = float(rng.choice([rng.uniform(0.01, 0.99), 0.5, 0.999, 0.9995, 1.0,
                                      1e-300, 0.0]))
        options = DecodeOptions(6, 128, 128, 128, 128, min_score=min_score,
                                score_clipping=float(rng.choice([100.0, 3.0])))
        scores = rng.normal(-8, 3, (1, 896, 1)).astype(np.float32)
        if 0 < min_score < 1:
            # The best anchor a few float32 steps from the threshold's logit, or a few units.
            best = np.float32(np.log(min_score / (1 - min_score)))
            if trial % 2:
                towards = np.float32(rng.choice([-np.inf, np.inf]))
                for _ in range(rng.integers(0, 4)):
                    best = np.nextafter(best, towards)
            else:
                best = np.float32(best + rng.uniform(-3, 3))
            scores[0, rng.integers(896), 0] = best
        keep = sigmoid_keeps(scores, options)
        found = decode(regressors, scores, anchors, options)
        skipped += not len(keep)
        assert len(found) == len(keep), (min_score, options.score_clipping)
        if len(keep):
            assert found.scores.tolist() == (1 / (1 + np.exp(-np.clip(
                scores.reshape(-1)[keep], -options.score_clipping, options.score_clipping
            ).astype(np.float64)))).astype(np.float32).tolist()
    assert 500 < skipped < 2500  # both ways were tried
    nan = np.full((1, 896, 1), np.nan, np.float32)
    assert len(decode(regressors, nan, anchors, DecodeOptions(6, 128, 128, 128, 128))) == 0


def test_decode_refuses_too_few_values_per_anchor():
    with pytest.raises(ValueError, match='regressors have 16 values per anchor, the options '
                                         'want 18'):
        decode(np.zeros((896, 16)), np.zeros(896), ssd_anchors(FACE),
               DecodeOptions(7, 128, 128, 128, 128))


def test_iou():
    box = np.array([0, 0, 2, 2], np.float32)
    boxes = np.array([[0, 0, 2, 2], [1, 0, 3, 2], [5, 5, 6, 6], [1, 1, 1, 1]], np.float32)
    assert iou(box, boxes) == pytest.approx([1.0, 1 / 3, 0.0, 0.0])


def detections(boxes, scores):
    boxes = np.array(boxes, np.float32)
    keypoints = np.stack([boxes[:, :2], boxes[:, 2:]], axis=1)
    return Detections(boxes, keypoints, np.array(scores, np.float32))


def test_weighted_nms_merges_overlaps_by_score_and_keeps_the_rest():
    found = weighted_nms(detections([[0.0, 0, 1, 1], [0.1, 0, 1.1, 1], [3, 3, 4, 4]],
                                    [0.6, 0.9, 0.7]), threshold=0.3)
    assert len(found) == 2
    assert found.scores.tolist() == pytest.approx([0.9, 0.7])
    # The two overlapping ones, weighted 0.9 and 0.6: x min = (0.9 * 0.1 + 0.6 * 0) / 1.5.
    assert found.boxes[0] == pytest.approx([0.06, 0, 1.06, 1])
    assert found.keypoints[0] == pytest.approx(np.array([[0.06, 0], [1.06, 1]]))
    assert found.boxes[1] == pytest.approx([3, 3, 4, 4])


def test_weighted_nms_limit_and_nothing():
    many = detections([[i * 2.0, 0, i * 2 + 1, 1] for i in range(5)], [0.5, 0.9, 0.6, 0.8, 0.7])
    assert weighted_nms(many, limit=2).scores.tolist() == pytest.approx([0.9, 0.8])
    empty = weighted_nms(detections(np.zeros((0, 4)), []))
    assert len(empty) == 0 and empty.boxes.shape == (0, 4)
