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

"""A user's own steps, for test_vision_step: one a case (a step, a plain class, broken ones)."""

import os

from py_vision.params import Spec
from py_vision.steps.api import Step
from std_msgs.msg import String


class Invert(Step):
    PARAMETERS = (
        Spec('gain', 1.0, 'how bright the inverted image is', (0.0, 4.0), live=True),
        Spec('label', 'inv', 'what it calls itself', choices=('inv', 'neg')),
    )

    def start(self, context):
        self.gain = context.parameters['gain']
        self.said = context.create_publisher(String, 'user_step/said')
        return 'gain %g, label %s' % (self.gain, context.parameters['label'])

    def parameters_changed(self, changes):
        self.gain = changes['gain']

    def process(self, image, header):
        self.said.publish(String(data='%s gain %g' % (header.frame_id, self.gain)))
        if header.frame_id == 'nothing':
            return None
        return 255 - image


class Plain:
    def process(self, image, header):
        return image[:, ::-1].copy()


class Failing(Step):
    def process(self, image, header):
        if header.frame_id == 'bad':
            raise ValueError('cannot read frame %d' % header.stamp.sec)
        if header.frame_id == 'wrong':
            return 'an answer'
        return image


class OwnModel(Step):
    # A model run by the user's own runtime, counted as one with model_time.timing().
    def process(self, image, header):
        import time
        from py_vision.models.model_time import timing
        with timing():
            time.sleep(0.05)
        return image


class NotAStep:
    pass


class BadInit(Step):
    def __init__(self):
        raise RuntimeError('no licence key')


class BadModel(Step):
    def start(self, context):
        from py_vision.models.runtime import load
        load(os.environ['USER_STEP_MODEL'])
