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
The `faces` step: MediaPipe's short-range face detector; boxes drawn and published.

The boxes go out as vision_msgs/Detection2DArray on `detections` (header: the frame's) where
vision_msgs is installed (meta-ros builds it for the boards). Where it is not (no wheel of it
exists on PyPI, so not on a PC with ROS from pip), the same data goes out as JSON in a
std_msgs/String on `detections_json`, and the start-up line says so:

    {"header": {"stamp": {"sec": 1, "nanosec": 0}, "frame_id": "camera"},
     "detections": [{"class_id": "face", "score": 0.93,
                     "bbox": {"center_x": 220.5, "center_y": 90.0,
                              "size_x": 64.0, "size_y": 64.0},
                     "keypoints": [[204.1, 80.2], ...]}]}

(pixels; a box's center and size as BoundingBox2D has them; keypoints: right eye, left eye,
nose tip, mouth, right ear tragion, left ear tragion, as MediaPipe orders them).
"""

import json
from typing import Any, Callable, Dict, List, Optional

import cv2
import numpy as np
from py_vision.models.faces import Face, FaceDetector, MODEL_FILE as FACE_MODEL
from py_vision.params import Spec
from py_vision.steps.api import Step, StepContext
from std_msgs.msg import String

CLASS_ID = 'face'
BOX_BGR = (0, 255, 0)


def detection_dicts(faces: List[Face]) -> List[Dict[str, Any]]:
    """Return the faces as the JSON fallback's `detections` list."""
    out = []
    for face in faces:
        x, y, w, h = (float(v) for v in face.box)
        out.append({'class_id': CLASS_ID, 'score': float(face.score),
                    'bbox': {'center_x': x + w / 2, 'center_y': y + h / 2,
                             'size_x': w, 'size_y': h},
                    'keypoints': [[float(a), float(b)] for a, b in np.asarray(face.keypoints)]})
    return out


def json_message(header: Any, faces: List[Face]) -> String:
    """Return the fallback message: header and detections as JSON in a std_msgs/String."""
    return String(data=json.dumps({
        'header': {'stamp': {'sec': header.stamp.sec, 'nanosec': header.stamp.nanosec},
                   'frame_id': header.frame_id},
        'detections': detection_dicts(faces)}))


def vision_msgs_publisher(context: StepContext, topic: str):
    """Return (publisher, make message) for vision_msgs, or None where it is not installed."""
    try:
        from vision_msgs.msg import Detection2D, Detection2DArray, ObjectHypothesisWithPose
    except ImportError:
        return None

    def message(header, faces: List[Face]):
        array = Detection2DArray(header=header)
        for item in detection_dicts(faces):
            detection = Detection2D(header=header)
            box = item['bbox']
            # vision_msgs 4 (Humble on): center is a Pose2D with a position; 3: x and y.
            center = getattr(detection.bbox.center, 'position', detection.bbox.center)
            center.x, center.y = box['center_x'], box['center_y']
            detection.bbox.size_x, detection.bbox.size_y = box['size_x'], box['size_y']
            hypothesis = ObjectHypothesisWithPose()
            hypothesis.hypothesis.class_id = CLASS_ID
            hypothesis.hypothesis.score = item['score']
            detection.results.append(hypothesis)
            array.detections.append(detection)
        return array
    return context.create_publisher(Detection2DArray, topic), message


class Faces(Step):
    """Faces found, boxed, and published as detections."""

    PARAMETERS = (
        Spec('min_score', 0.5, 'faces scoring less than this are left out (the detector '
             'decodes at it, down to 0)', (0.0, 1.0), live=True),
        Spec('detections_topic', 'detections', 'where the detections go (vision_msgs); '
             'without vision_msgs, JSON on this name + _json', check=bool,
             accepted='a topic name'),
    )

    def __init__(self):
        self.detector: Optional[FaceDetector] = None
        self.publisher = None
        self.message: Callable[[Any, List[Face]], Any] = json_message

    def start(self, context: StepContext) -> Optional[str]:
        """Load the model; publish vision_msgs where installed, else the JSON fallback."""
        # The detector decodes at min_score: below MediaPipe's 0.5 too, down to 0.
        self.detector = FaceDetector.from_file(context.model_path(FACE_MODEL),
                                               threads=context.threads,
                                               min_score=context.parameters['min_score'])
        topic = context.parameters['detections_topic']
        found = vision_msgs_publisher(context, topic)
        if found is None:
            self.publisher = context.create_publisher(String, topic + '_json')
            what = ('vision_msgs is not installed: detections as JSON (std_msgs/String) on %s'
                    % self.publisher.topic_name)
        else:
            self.publisher, self.message = found
            what = 'detections (vision_msgs/Detection2DArray) on %s' % self.publisher.topic_name
        return '%s; %s; %s' % (self.detector.model.runtime, FACE_MODEL, what)

    def parameters_changed(self, changes: Dict[str, Any]) -> Optional[str]:
        """Take a new min_score (the detector's threshold from the next frame on)."""
        self.detector.min_score = changes['min_score']
        return None

    def process(self, image: np.ndarray, header: Any) -> Optional[np.ndarray]:
        """Detect, publish the detections with the frame's header, draw the boxes."""
        faces = self.detector.detect(image)
        self.publisher.publish(self.message(header, faces))
        for face in faces:
            x, y, w, h = (int(round(float(v))) for v in face.box)
            cv2.rectangle(image, (x, y), (x + w, y + h), BOX_BGR, 2)
            cv2.putText(image, '%.2f' % face.score, (x, max(y - 5, 12)),
                        cv2.FONT_HERSHEY_SIMPLEX, 0.5, BOX_BGR, 1, cv2.LINE_AA)
        return image
