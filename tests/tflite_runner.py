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
Run .tflite models on saved inputs with tflite_runtime, in whichever Python runs this file.

    python -I tflite_runner.py SITE MODELS CASES OUT

SITE is a folder holding numpy and tflite_runtime (put first on sys.path, before anything the
interpreter has); each CASES/<model>/<case>.npy is an input of MODELS/<model>.tflite, and the
model's outputs for it are written to OUT/<model>/<case>.<n>.npy, n the output's index. One
interpreter thread, with tflite_runtime's defaults (the XNNPACK delegate), as
py_vision.models.runtime loads a model. OUT/about.json says what ran: the machine, the Python,
numpy and tflite_runtime versions, and the seconds each model took per run.

test_aarch64_models.py runs it in the aarch64 Python under QEMU and in an x86-64 one. It needs
nothing but numpy and tflite_runtime: no py_vision, no OpenCV.
"""

import json
import os
import platform
import sys
import time


def main(site: str, models: str, cases: str, out: str) -> None:
    """Run every model on each of its cases, write the outputs and about.json."""
    sys.path.insert(0, site)
    import numpy
    import tflite_runtime
    from tflite_runtime.interpreter import Interpreter

    seconds = {}
    for model in sorted(os.listdir(cases)):
        interpreter = Interpreter(model_path=os.path.join(models, model + '.tflite'),
                                  num_threads=1)
        interpreter.allocate_tensors()
        (tensor,) = interpreter.get_input_details()
        os.makedirs(os.path.join(out, model), exist_ok=True)
        times = []
        for case in sorted(os.listdir(os.path.join(cases, model))):
            interpreter.set_tensor(tensor['index'],
                                   numpy.load(os.path.join(cases, model, case)))
            start = time.monotonic()
            interpreter.invoke()
            times.append(time.monotonic() - start)
            for number, output in enumerate(interpreter.get_output_details()):
                numpy.save(os.path.join(out, model, '%s.%d.npy' % (case[:-4], number)),
                           interpreter.get_tensor(output['index']))
        seconds[model] = times
    about = {'machine': platform.machine(), 'python': platform.python_version(),
             'numpy': numpy.__version__, 'tflite_runtime': tflite_runtime.__version__,
             'seconds': seconds}
    with open(os.path.join(out, 'about.json'), 'w') as about_file:
        json.dump(about, about_file)


if __name__ == '__main__':
    main(*sys.argv[1:5])
