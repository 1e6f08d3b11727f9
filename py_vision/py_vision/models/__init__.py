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
Models on camera frames, without ROS: the runtimes and MediaPipe's hand and face models.

- `runtime`: `load(path)` a .tflite or .onnx model into whichever runtime is installed
  (`Model`, `ModelError`, `RuntimeMissing`), quantised ones fed and read in float;
  `find_outputs`, a model's outputs by name;
- `model_time`: the time a thread spent inside models (each runtime's run, timed), which
  vision_step reports beside a frame's processing time;
- `onnx_graph`: an ONNX file's inputs and outputs (and their quantisation), read without the
  onnx package;
- `files`: `shipped_model(name)`, the model files installed with the package;
- `anchors`: SSD anchors, decoding of boxes and keypoints, non-maximum suppression (shared by
  the palm and the face detector);
- `palm` and `hands`: `HandTracker`, the palm detector and the hand landmark model (`Hand`);
- `faces`: `FaceDetector`, the short-range face detector (`Face`);
- `signs`: `classify(landmarks, handedness)`, a handful of hand signs from 21 landmarks.
"""
