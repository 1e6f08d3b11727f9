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
SSD anchors and the decoding of an SSD detector's raw output, as MediaPipe's detectors use them.

A MediaPipe detector (the palm detector, the face detector) predicts, for each of a fixed list
of anchors (boxes on a grid over the model's input), a box and a few keypoints as offsets from
the anchor, and a raw score. `ssd_anchors` makes that list (MediaPipe's SsdAnchorsCalculator:
layers of the same stride share a grid, each cell has one anchor per aspect ratio plus one
interpolated between this layer's scale and the next); `decode` turns the raw regressors and
scores into boxes, keypoints and scores (TensorsToDetectionsCalculator: the offsets are in
input pixels, x before y, scores are clipped logits through a sigmoid); `weighted_nms` merges
the many overlapping detections of one object into one, averaging their boxes and keypoints
weighted by score (NonMaxSuppressionCalculator's WEIGHTED algorithm). Coordinates are
normalized to the model's input: 0 to 1 across its width and height. `SsdDetector` does it
all on a camera frame: letterboxed into the model's input, run, decoded, merged, and the boxes
and keypoints mapped back to the frame's pixels (the palm and the face detector).
"""

from dataclasses import dataclass, replace
import math
from typing import List, Sequence, Tuple

import numpy as np
from py_vision.models.crops import InputBuffers, letterbox
from py_vision.models.runtime import find_outputs, Model

__all__ = ['AnchorOptions', 'decode', 'DecodeOptions', 'Detections', 'iou', 'SsdDetector',
           'SsdModel', 'ssd_anchors', 'weighted_nms']


@dataclass(frozen=True)
class AnchorOptions:
    """SsdAnchorsCalculator's options (MediaPipe's names), for fixed-size anchors."""

    input_width: int
    input_height: int
    strides: Tuple[int, ...]
    min_scale: float = 0.1484375
    max_scale: float = 0.75
    offset_x: float = 0.5
    offset_y: float = 0.5
    aspect_ratios: Tuple[float, ...] = (1.0,)
    interpolated_scale_aspect_ratio: float = 1.0
    fixed_anchor_size: bool = True


@dataclass(frozen=True)
class DecodeOptions:
    """TensorsToDetectionsCalculator's options for a one-class detector (x, y, w, h first)."""

    num_keypoints: int
    x_scale: float
    y_scale: float
    w_scale: float
    h_scale: float
    min_score: float = 0.5
    score_clipping: float = 100.0


@dataclass
class Detections:
    """
    Detections, normalized to the model's input.

    boxes: (K, 4) xmin, ymin, xmax, ymax; keypoints: (K, num_keypoints, 2) x, y; scores: (K,).
    """

    boxes: np.ndarray
    keypoints: np.ndarray
    scores: np.ndarray

    def __len__(self) -> int:
        return len(self.scores)


def _scale(options: AnchorOptions, index: int) -> float:
    count = len(options.strides)
    if count == 1:
        return (options.min_scale + options.max_scale) / 2
    return options.min_scale + (options.max_scale - options.min_scale) * index / (count - 1)


def ssd_anchors(options: AnchorOptions) -> np.ndarray:
    """Return the anchors, (N, 4): x_center, y_center, width, height, in the models' order."""
    anchors = []
    strides = options.strides
    layer = 0
    while layer < len(strides):
        shapes = []  # (scale, aspect ratio) of each anchor in one grid cell
        last = layer
        while last < len(strides) and strides[last] == strides[layer]:
            scale = _scale(options, last)
            shapes += [(scale, ratio) for ratio in options.aspect_ratios]
            if options.interpolated_scale_aspect_ratio > 0:
                following = 1.0 if last == len(strides) - 1 else _scale(options, last + 1)
                shapes.append((math.sqrt(scale * following),
                               options.interpolated_scale_aspect_ratio))
            last += 1
        rows = int(math.ceil(options.input_height / strides[layer]))
        columns = int(math.ceil(options.input_width / strides[layer]))
        for row in range(rows):
            for column in range(columns):
                x = (column + options.offset_x) / columns
                y = (row + options.offset_y) / rows
                for scale, ratio in shapes:
                    if options.fixed_anchor_size:
                        anchors.append((x, y, 1.0, 1.0))
                    else:
                        anchors.append((x, y, scale * math.sqrt(ratio),
                                        scale / math.sqrt(ratio)))
        layer = last
    return np.array(anchors, dtype=np.float32)


def decode(regressors: np.ndarray, raw_scores: np.ndarray, anchors: np.ndarray,
           options: DecodeOptions) -> Detections:
    """
    Decode one image's raw output into the detections scoring at least options.min_score.

    regressors: (N, 4 + 2 * num_keypoints) (a leading batch axis of 1 is dropped);
    raw_scores: N logits; anchors: ssd_anchors' (N, 4).
    """
    regressors = regressors.reshape(len(anchors), -1)
    if regressors.shape[1] < 4 + 2 * options.num_keypoints:
        raise ValueError('regressors have %d values per anchor, the options want %d'
                         % (regressors.shape[1], 4 + 2 * options.num_keypoints))
    count = options.num_keypoints
    raw_scores = raw_scores.reshape(-1)
    if _none_near(raw_scores, options):  # the usual frame: nothing to decode
        return _no_detections(count)
    logits = np.clip(raw_scores, -options.score_clipping, options.score_clipping)
    scores = 1.0 / (1.0 + np.exp(-logits.astype(np.float64)))
    keep = np.flatnonzero(scores >= options.min_score)
    if not len(keep):  # no anchor scores enough
        return _no_detections(count)
    raw = regressors[keep].astype(np.float64)
    anchor = anchors[keep].astype(np.float64)
    scale = np.array([options.x_scale, options.y_scale])
    size = anchor[:, 2:4]
    centers = raw[:, 0:2] / scale * size + anchor[:, 0:2]
    half = raw[:, 2:4] / np.array([options.w_scale, options.h_scale]) * size / 2
    boxes = np.concatenate([centers - half, centers + half], axis=1)
    points = raw[:, 4:4 + 2 * count].reshape(len(keep), count, 2)
    keypoints = points / scale * size[:, None, :] + anchor[:, None, 0:2]
    return Detections(boxes.astype(np.float32), keypoints.astype(np.float32),
                      scores[keep].astype(np.float32))


# How far (in logits) below the threshold's logit the best anchor must be for decode() to skip
# the sigmoid of them all, and the highest threshold it does it for: there the sigmoid's
# float64 rounding (1e-16) is far below what the margin changes a score by (over 1e-10).
_LOGIT_MARGIN = 1e-6
_SKIP_UP_TO = 0.999


def _none_near(raw_scores: np.ndarray, options: DecodeOptions) -> bool:
    """
    Return True when no anchor can score min_score: the best logit is well below its logit.

    The sigmoid keeps the logits' order (so does the clipping): the best anchor's logit
    decides. One pass over the logits instead of their sigmoids; an anchor anywhere near the
    threshold (or a NaN) leaves the decision to the sigmoids, as before.
    """
    threshold = options.min_score
    if not len(raw_scores) or not 0.0 < threshold <= _SKIP_UP_TO:
        return False
    clip = options.score_clipping
    best = min(max(float(raw_scores.max()), -clip), clip)
    return best < math.log(threshold / (1.0 - threshold)) - _LOGIT_MARGIN


def _no_detections(num_keypoints: int) -> Detections:
    return Detections(np.empty((0, 4), np.float32), np.empty((0, num_keypoints, 2), np.float32),
                      np.empty(0, np.float32))


def iou(box: np.ndarray, boxes: np.ndarray) -> np.ndarray:
    """Return the intersection over union of box with each of boxes (xmin, ymin, xmax, ymax)."""
    low = np.maximum(box[:2], boxes[:, :2])
    high = np.minimum(box[2:], boxes[:, 2:])
    intersection = np.prod(np.clip(high - low, 0, None), axis=1)
    area = np.prod(np.clip(box[2:] - box[:2], 0, None))
    areas = np.prod(np.clip(boxes[:, 2:] - boxes[:, :2], 0, None), axis=1)
    union = area + areas - intersection
    return np.where(union > 0, intersection / np.where(union > 0, union, 1), 0.0)


def weighted_nms(detections: Detections, threshold: float = 0.3,
                 limit: int = 0) -> Detections:
    """
    Merge overlapping detections: best score first, each with all that overlap it.

    Every detection whose IoU with the best remaining one exceeds `threshold` joins it; the
    group becomes one detection with the score-weighted mean box and keypoints and the best
    one's score. Returns at most `limit` detections (0: all), best first.
    """
    if not len(detections):
        return _no_detections(detections.keypoints.shape[1])
    order = np.argsort(-detections.scores, kind='stable')
    boxes, keypoints, scores = [], [], []
    while len(order) and (not limit or len(scores) < limit):
        overlaps = iou(detections.boxes[order[0]], detections.boxes[order])
        group = order[overlaps > threshold]
        if not len(group):  # a box of no area overlaps nothing, not even itself
            group = order[:1]
        order = order[np.isin(order, group, invert=True)]
        weights = detections.scores[group].astype(np.float64)
        weights = weights / weights.sum()
        boxes.append(np.tensordot(weights, detections.boxes[group], axes=1))
        keypoints.append(np.tensordot(weights, detections.keypoints[group], axes=1))
        scores.append(detections.scores[group[0]])
    count = len(scores)
    width = detections.keypoints.shape[1]
    return Detections(np.array(boxes, np.float32).reshape(count, 4),
                      np.array(keypoints, np.float32).reshape(count, width, 2),
                      np.array(scores, np.float32))


@dataclass(frozen=True)
class SsdModel:
    """
    What tells one MediaPipe SSD detector model from another.

    size: its square input, pixels a side; value_range: the input's values (black, white);
    outputs: the regressors' and the scores' (names, shape), as runtime.find_outputs takes them.
    """

    size: int
    num_keypoints: int
    value_range: Tuple[float, float]
    outputs: Sequence[Tuple[Sequence[str], Tuple[int, ...]]]
    strides: Tuple[int, ...] = (8, 16, 16, 16)


class SsdDetector:
    """
    A square SSD detector run on whole bgr8 frames (the palm and the face detector).

    `detections(frame)` letterboxes the frame into the model's input, runs it, decodes the
    anchors scoring at least `min_score`, merges them (weighted NMS at `nms_threshold`, at most
    `limit`, 0: all) and returns (box, score, keypoints), best first: box (x, y, w, h) and
    keypoints (num_keypoints, 2) in frame pixels, float32. `min_score` may change while another
    thread detects: that detection uses the old value or the new one.
    """

    def __init__(self, model: Model, spec: SsdModel, min_score: float, nms_threshold: float,
                 limit: int):
        """Use a loaded model of that spec (ModelError: another model)."""
        self._outputs = find_outputs(model, [(1, spec.size, spec.size, 3)], spec.outputs)
        self.model = model
        self.spec = spec
        self.nms_threshold = nms_threshold
        self.limit = limit
        self._anchors = ssd_anchors(AnchorOptions(spec.size, spec.size, spec.strides))
        self._buffers = InputBuffers()  # the model's input, made in the same arrays each frame
        size = spec.size
        self._decoding = DecodeOptions(spec.num_keypoints, size, size, size, size, min_score)

    @property
    def min_score(self) -> float:
        """Return the score a detection needs (0 to 1; the anchors are decoded at it)."""
        return self._decoding.min_score

    @min_score.setter
    def min_score(self, value: float) -> None:
        # One assignment: a detection under way on another thread uses the old or the new one.
        self._decoding = replace(self._decoding, min_score=float(value))

    def detections(self, image_bgr: np.ndarray) -> List[Tuple[np.ndarray, float, np.ndarray]]:
        """Return the frame's detections, best first: (box, score, keypoints) in frame pixels."""
        size = self.spec.size
        decoding = self._decoding
        crop = letterbox(image_bgr, size, size, self.spec.value_range, self._buffers)
        results = self.model.run(crop.tensor)
        regressors, scores = (results[index] for index in self._outputs)
        found = weighted_nms(decode(regressors, scores, self._anchors, decoding),
                             self.nms_threshold, self.limit)
        detections = []
        for box, keypoints, score in zip(found.boxes, found.keypoints, found.scores):
            corners = crop.points_to_image(box.reshape(2, 2) * size)
            detections.append((np.array([corners[0, 0], corners[0, 1],
                                         corners[1, 0] - corners[0, 0],
                                         corners[1, 1] - corners[0, 1]], np.float32),
                               float(score),
                               crop.points_to_image(keypoints * size).astype(np.float32)))
        return detections
