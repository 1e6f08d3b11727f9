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

"""The test cameras' one description: data files, the USB 2.0 rule, the synthetic camera."""

from emulated_camera import CAMERAS, load_model, model_path
from py_vision.capture import camera_model
from py_vision.capture.controls import CID
from py_vision.capture.pixel_formats import find
from py_vision.capture.synthetic_device import SyntheticCamera
import pytest

MODELS = sorted(path.stem for path in CAMERAS.glob('*.yaml')) + ['synthetic']


@pytest.mark.parametrize('fourcc,width,height,rates', [
    ('YUYV', 640, 480, (30.0, 25.0, 20.0, 15.0, 10.0, 5.0)),   # 18.4 MB/s at 30
    ('YUYV', 800, 600, (25.0, 20.0, 15.0, 10.0, 5.0)),
    ('YUYV', 1280, 720, (10.0, 5.0)),
    ('YUYV', 1920, 1080, (5.0,)),                             # 20.7 MB/s at 5
    ('YUYV', 3840, 2160, (5.0,)),                             # none fits: the slowest
    ('GREY', 1280, 720, (25.0, 20.0, 15.0, 10.0, 5.0)),        # one byte a pixel
    ('NV12', 1920, 1080, (5.0,)),
    ('MJPG', 3840, 2160, (30.0, 25.0, 20.0, 15.0, 10.0, 5.0)),  # compressed: every rate
])
def test_a_usb2_camera_offers_the_rates_whose_frames_fit_the_bus(fourcc, width, height, rates):
    assert camera_model.bus_rates(find(fourcc), width, height,
                                  (5, 10, 15, 20, 25, 30)) == rates


@pytest.mark.parametrize('model', MODELS)
def test_every_camera_file_reads_and_the_emulator_offers_what_the_rule_gives(model):
    described = camera_model.load(model_path(model))
    emulated = load_model(model)
    assert [fmt['fourcc'] for fmt in emulated['formats']] == [
        fmt.pixel_format.fourcc for fmt in described.formats]
    for fmt, offered in zip(emulated['formats'], described.formats):
        for frame in fmt['frames']:
            assert tuple(frame['rates']) == camera_model.bus_rates(
                offered.pixel_format, frame['width'], frame['height'], offered.rates,
                described.bandwidth)
    assert [c['id'] for c in emulated['controls']] == [c.info.cid for c in described.controls]


def test_the_synthetic_camera_is_its_data_file():
    # What the synthetic camera lists and reports is what the emulator serves from the file.
    described = camera_model.load(camera_model.SYNTHETIC)
    camera = SyntheticCamera(640, 480, 30.0)
    listed = camera.formats()
    assert [fmt.fourcc for fmt in listed] == [f.pixel_format.fourcc for f in described.formats]
    for fmt, offered in zip(listed, described.formats):
        assert fmt.sizes == described.frame_sizes(offered)
    assert [c.cid for c in camera.controls()] == [c.info.cid for c in described.controls]
    for control, entry in zip(camera.controls(), described.controls):
        info = entry.info
        assert (control.label, control.kind, control.minimum, control.maximum, control.default,
                control.menu) == (info.label, info.kind, info.minimum, info.maximum,
                                  info.default, info.menu)
        assert control.value == info.default


def test_a_control_the_file_says_an_automatic_mode_holds_is_inactive_while_it_does():
    camera = SyntheticCamera(160, 120, 10.0)
    inactive = {control.cid for control in camera.controls() if control.inactive}
    assert inactive == {CID.WHITE_BALANCE_TEMPERATURE, CID.EXPOSURE_ABSOLUTE,
                        CID.FOCUS_ABSOLUTE}
    assert camera.set_control(CID.EXPOSURE_AUTO, 1) is None   # manual
    assert camera.set_control(CID.AUTO_WHITE_BALANCE, 0) is None
    inactive = {control.cid for control in camera.controls() if control.inactive}
    assert inactive == {CID.FOCUS_ABSOLUTE}


@pytest.mark.parametrize('text,says', [
    ('formats: []\n', 'needs formats'),
    ('formats: [{fourcc: XXXX, sizes: [[8, 8]], rates: [30]}]\n', 'no pixel format XXXX'),
    ('formats: [{fourcc: YUYV, sizes: [[8, 8]], rates: []}]\n', 'YUYV needs sizes and rates'),
    ('formats: [{fourcc: YUYV, sizes: [[8, 8]], rates: [30]}]\n'
     'controls: [{name: a, id: 1, label: A, type: float}]\n', "a has type 'float'"),
    ('formats: [{fourcc: YUYV, sizes: [[8, 8]], rates: [30]}]\n'
     'controls: [{name: a, id: 1, label: A, type: integer, effect: blur}]\n',
     "a has effect 'blur'"),
    ('formats: [{fourcc: YUYV, sizes: [[8, 8]], rates: [30]}]\n'
     'controls: [{name: a, id: 1, label: A, type: integer, inactive_unless: {b: 0}}]\n',
     'a depends on unknown control b'),
    ('formats: [{fourcc: YUYV\n', 'cannot read the camera'),
])
def test_a_bad_data_file_is_one_error_naming_the_file_and_the_fault(tmp_path, text, says):
    path = tmp_path / 'bad.yaml'
    path.write_text(text)
    with pytest.raises(ValueError) as error:
        camera_model.load(path)
    assert str(error.value).startswith(str(path) + ': ') and '\n' not in str(error.value)
    assert says in str(error.value)
