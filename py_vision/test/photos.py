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
Real photographs for the model tests: the pictures scikit-image ships, read by path, and a hand.

scikit-image's wheel carries a few photographs in skimage/data/ (astronaut.png is NASA's
portrait of Eileen Collins, public domain). They are read with OpenCV from the installed
package's folder, without importing skimage (whose import differs between its versions).

No Python package ships a photograph of a hand. Debian's opencv-doc package does: OpenCV's
documentation's handSrc.jpg, an open left hand on a table, palm up, fingers to the right
(640x480). scripts/test.sh takes that one file out of the package (PY_VISION_HAND_PHOTO names
it); where opencv-doc is installed it is read from there. Without it the tests that need it are
skipped with the reason, and fail in CI.
"""

import importlib.util
import os

import cv2
import numpy as np
import pytest

HAND_PHOTO_INSTALLED = '/usr/share/doc/opencv-doc/opencv4/html/handSrc.jpg'


def photo(name: str) -> np.ndarray:
    """Return the photograph skimage/data/<name> as a bgr8 image."""
    spec = importlib.util.find_spec('skimage')
    assert spec is not None, 'scikit-image is not installed (requirements-test.txt)'
    path = os.path.join(spec.submodule_search_locations[0], 'data', name)
    image = cv2.imread(path, cv2.IMREAD_COLOR)
    assert image is not None, 'cannot read %s' % path
    return image


def hand_photo() -> np.ndarray:
    """Return OpenCV's documentation's photograph of an open left hand, bgr8 640x480."""
    path = os.environ.get('PY_VISION_HAND_PHOTO') or HAND_PHOTO_INSTALLED
    image = cv2.imread(path, cv2.IMREAD_COLOR)
    if image is None:
        why = ("no photograph of a hand at %s (scripts/test.sh takes it out of Debian's "
               'opencv-doc package; or apt-get install opencv-doc)' % path)
        if os.environ.get('CI') == 'true':
            pytest.fail(why + ', and CI requires it')
        pytest.skip(why)
    return image
