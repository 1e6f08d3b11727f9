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
The time inside models (model_time): per thread, counted by every runtime around its run alone.

What vision_step splits a frame's processing time with: a model's run counts once, with no
more than the run took, on the thread that ran it and no other.
"""

import threading
import time

from fake_clock import FakeClock
import numpy as np
import onnx_model
from py_vision.models.files import shipped_model
from py_vision.models.model_time import ModelTime, thread_model_time, timing
from py_vision.models.runtime import load
import pytest

# Each runtime is optional: a test of one this run lacks is skipped, saying which.
MODULES = {'litert': 'ai_edge_litert', 'tflite_runtime': 'tflite_runtime',
           'onnxruntime': 'onnxruntime', 'opencv': 'cv2'}


def test_timing_adds_the_blocks_time_its_cpu_time_and_one_run_to_the_thread():
    clock, cpu = FakeClock(50.0), FakeClock(3.0)
    before = thread_model_time()
    with timing(clock, cpu):
        clock.t += 0.25
        cpu.t += 0.125  # the rest of the time the thread waited for a core
    with timing(clock, cpu):
        clock.t += 0.5
        cpu.t += 0.5
    clock.t += 7.0  # outside any block: not a model's time
    cpu.t += 7.0
    assert thread_model_time().since(before) == ModelTime(0.75, 2, 0.625)


def test_a_run_that_raises_is_counted_too():
    clock = FakeClock()
    before = thread_model_time()
    with pytest.raises(RuntimeError):
        with timing(clock, clock):
            clock.t += 0.125
            raise RuntimeError('the model failed')
    assert thread_model_time().since(before) == ModelTime(0.125, 1, 0.125)


def test_another_threads_runs_are_not_this_threads():
    clock = FakeClock()
    before = thread_model_time()
    other = []

    def elsewhere():
        start = thread_model_time()
        with timing(clock, clock):
            clock.t += 2.0
        other.append(thread_model_time().since(start))
    thread = threading.Thread(target=elsewhere)
    thread.start()
    thread.join(10.0)
    assert other == [ModelTime(2.0, 1, 2.0)]
    assert thread_model_time().since(before) == ModelTime(0.0, 0, 0.0)


def timed_run(model, array):
    """Return (the run's wall time, what the thread's model time grew by)."""
    before = thread_model_time()
    start = time.monotonic()
    model.run(array)
    took = time.monotonic() - start
    return took, thread_model_time().since(before)


@pytest.mark.parametrize('runtime', ['litert', 'tflite_runtime'])
def test_a_tflite_models_run_counts_once_and_no_more_than_it_took(runtime):
    pytest.importorskip(MODULES[runtime])
    model = load(shipped_model('palm_detection_lite.tflite'), runtime=runtime)
    took, inside = timed_run(model, np.zeros((1, 192, 192, 3), np.float32))
    assert inside.runs == 1
    assert 0 < inside.seconds <= took
    assert 0 < inside.cpu_seconds  # the run computes on this thread (1 thread)


@pytest.mark.parametrize('runtime', ['opencv', 'onnxruntime'])
def test_an_onnx_models_run_counts_once_and_no_more_than_it_took(runtime, tmp_path):
    pytest.importorskip(MODULES[runtime])
    model = load(onnx_model.write(str(tmp_path / 'tiny.onnx')), runtime=runtime)
    took, inside = timed_run(model, np.zeros(onnx_model.INPUT_SHAPE, np.float32))
    assert inside.runs == 1
    assert 0 < inside.seconds <= took


def test_a_run_refused_before_the_model_runs_is_not_a_model_run():
    model = load(shipped_model('palm_detection_lite.tflite'))
    before = thread_model_time()
    with pytest.raises(Exception, match='wants shape'):
        model.run(np.zeros((1, 100, 100, 3), np.float32))
    assert thread_model_time().since(before) == ModelTime(0.0, 0, 0.0)
