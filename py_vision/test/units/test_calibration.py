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

"""Calibration URLs, camera_calibration YAML files and CameraInfoManager, without a node."""

import errno
import math
import os
import tempfile
import threading

from hypothesis import given, settings, strategies as st
import numpy as np
from py_vision import calibration
from py_vision.calibration import (CalibrationError, CameraInfoManager, dump_calibration,
                                   load_calibration, resolve_url, validate_camera_info)
import pytest
from sensor_msgs.msg import CameraInfo

# What cameracalibrator's "commit" / "save" writes for a 640x480 plumb_bob calibration, with its
# number formatting (numpy's array2string, wrapped lines) and no binning or roi.
CALIBRATOR_YAML = """\
image_width: 640
image_height: 480
camera_name: usb_camera
camera_matrix:
  rows: 3
  cols: 3
  data: [612.41893,   0.     , 318.73549,
           0.     , 611.90524, 244.12806,
           0.     ,   0.     ,   1.     ]
distortion_model: plumb_bob
distortion_coefficients:
  rows: 1
  cols: 5
  data: [0.112378, -0.235867, 0.001052, -0.000731, 0.000000]
rectification_matrix:
  rows: 3
  cols: 3
  data: [1., 0., 0.,
         0., 1., 0.,
         0., 0., 1.]
projection_matrix:
  rows: 3
  cols: 4
  data: [619.82617,   0.     , 318.15247,   0.     ,
           0.     , 620.04431, 244.37952,   0.     ,
           0.     ,   0.     ,   1.     ,   0.     ]
"""
K = [612.41893, 0, 318.73549, 0, 611.90524, 244.12806, 0, 0, 1]
D = [0.112378, -0.235867, 0.001052, -0.000731, 0.0]
R = [1, 0, 0, 0, 1, 0, 0, 0, 1]
P = [619.82617, 0, 318.15247, 0, 0, 620.04431, 244.37952, 0, 0, 0, 1, 0]


class RecordingLogger:
    """Stands in for the node's rclpy logger and keeps what was logged."""

    def __init__(self):
        self.lines = []

    def info(self, message):
        self.lines.append(('info', message))

    def warning(self, message):
        self.lines.append(('warning', message))

    def at(self, level):
        return [message for logged, message in self.lines if logged == level]


@pytest.fixture(autouse=True)
def ros_home(tmp_path, monkeypatch):
    """Keep the user's ~/.ros out of reach: ROS_HOME and HOME point into tmp_path."""
    home = tmp_path / 'ros_home'
    monkeypatch.setenv('ROS_HOME', str(home))
    monkeypatch.setenv('HOME', str(tmp_path / 'home'))
    return home


@pytest.fixture
def logger():
    return RecordingLogger()


def write(path, text):
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)
    return path


def make_info(fx=600.0, width=640, height=480, model='plumb_bob', d=(0.1, -0.2, 0.0, 0.0, 0.0)):
    info = CameraInfo(width=width, height=height, distortion_model=model)
    # Arrays, as a received message holds them: Humble's message refuses a list with a NaN (one
    # from the wire gets through all the same).
    info.k = np.array([fx, 0.0, width / 2, 0.0, fx, height / 2, 0.0, 0.0, 1.0])
    info.d = list(d)
    info.r = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]
    info.p = np.array([fx, 0.0, width / 2, 0.0, 0.0, fx, height / 2, 0.0, 0.0, 0.0, 1.0, 0.0])
    return info


def assert_calibration(info, k=K, d=D, r=R, p=P, width=640, height=480, model='plumb_bob'):
    assert (info.width, info.height) == (width, height)
    assert info.distortion_model == model
    assert list(info.k) == pytest.approx(k, abs=0, rel=0)
    assert list(info.d) == pytest.approx(d, abs=0, rel=0)
    assert list(info.r) == pytest.approx(r, abs=0, rel=0)
    assert list(info.p) == pytest.approx(p, abs=0, rel=0)


def assert_uncalibrated(info, width, height):
    """As camera_info_manager publishes it: the image size, everything else zero or empty."""
    assert (info.width, info.height) == (width, height)
    assert not any(info.k) and not any(info.r) and not any(info.p)
    assert len(info.d) == 0 and info.distortion_model == ''


# --- URLs ---

def test_file_url_names_its_absolute_path():
    assert resolve_url('file:///data/cam/left.yaml', 'usb_camera') == '/data/cam/left.yaml'
    assert resolve_url('FILE:///data/cam/left.yaml', 'usb_camera') == '/data/cam/left.yaml'


def test_name_is_substituted_with_the_camera_name():
    resolved = resolve_url('file:///data/${NAME}/${NAME}.yaml', 'front_1')
    assert resolved == '/data/front_1/front_1.yaml'


def test_empty_url_is_the_default_file_under_ros_home(ros_home):
    assert resolve_url('', 'usb_camera') == str(ros_home / 'camera_info' / 'usb_camera.yaml')
    assert resolve_url('file://${ROS_HOME}/cal.yaml', 'x') == str(ros_home / 'cal.yaml')


def test_without_ros_home_the_default_is_under_home_dot_ros(tmp_path, monkeypatch):
    monkeypatch.delenv('ROS_HOME')
    assert resolve_url('', 'cam') == str(tmp_path / 'home' / '.ros' / 'camera_info' / 'cam.yaml')


def test_package_url_is_found_through_the_ament_index():
    path = resolve_url('package://py_vision/config/example_calibration.yaml', 'usb_camera')
    assert path.endswith(os.path.join('share', 'py_vision', 'config', 'example_calibration.yaml'))
    name, info = load_calibration(path)
    assert name == 'usb_camera' and (info.width, info.height) == (640, 480)
    assert validate_camera_info(info) is None


@pytest.mark.parametrize('url, says', [
    ('http://example.com/cal.yaml', 'not a calibration URL'),
    ('/data/cal.yaml', 'not a calibration URL'),
    ('file://data/cal.yaml', 'absolute path'),
    ('package://no_such_package_here/cal.yaml', "package 'no_such_package_here' is not in the"),
    ('package://py_vision', 'expected package://<package>/<path>'),
    ('package://py_vision/', 'expected package://<package>/<path>'),
    ('file:///data/${CAMERA}.yaml', 'unknown substitution ${CAMERA}'),
])
def test_unusable_url_says_why(url, says):
    with pytest.raises(CalibrationError) as raised:
        resolve_url(url, 'usb_camera')
    assert says in str(raised.value) and url in str(raised.value)


def test_a_camera_name_cannot_leave_the_directory(logger):
    assert calibration.is_valid_camera_name('front_Left_2')
    assert not calibration.is_valid_camera_name('front-left')
    assert not calibration.is_valid_camera_name('')
    with pytest.raises(CalibrationError, match='letters, digits and _'):
        resolve_url('file:///data/${NAME}.yaml', '../etc/passwd')
    with pytest.raises(CalibrationError, match='letters, digits and _'):
        CameraInfoManager('front/left', '', logger)


# --- the YAML file ---

def test_cameracalibrator_yaml_loads_with_its_values(tmp_path):
    name, info = load_calibration(str(write(tmp_path / 'ost.yaml', CALIBRATOR_YAML)))
    assert name == 'usb_camera'
    assert_calibration(info)


@pytest.mark.parametrize('model, d', [
    ('plumb_bob', [0.1, -0.2, 0.001, 0.002, 0.03]),
    ('rational_polynomial', [0.1, -0.2, 0.001, 0.002, 0.03, 0.4, -0.05, 0.006]),
    ('equidistant', [0.01, -0.002, 0.0003, -0.00004]),
])
def test_every_distortion_model_round_trips(tmp_path, model, d):
    info = make_info(model=model, d=d)
    path = write(tmp_path / 'cal.yaml', dump_calibration('usb_camera', info))
    assert 'cols: %d' % len(d) in path.read_text()
    assert load_calibration(str(path)) == ('usb_camera', info)
    assert validate_camera_info(info) is None


@pytest.mark.parametrize('coefficients, model', [(5, 'plumb_bob'), (8, 'rational_polynomial')])
def test_a_file_without_distortion_model_gets_cameracalibrators_choice(
        tmp_path, coefficients, model):
    text = dump_calibration('cam', make_info(model=model, d=[0.01] * coefficients))
    text = text.replace('distortion_model: %s\n' % model, '')
    assert 'distortion_model' not in text
    _, info = load_calibration(str(write(tmp_path / 'old.yaml', text)))
    assert info.distortion_model == model


def test_camera_calibration_parsers_extras_are_read_and_written(tmp_path):
    info = make_info()
    info.binning_x, info.binning_y = 2, 2
    info.roi.x_offset, info.roi.y_offset, info.roi.width, info.roi.height = 8, 4, 320, 240
    info.roi.do_rectify = True
    path = write(tmp_path / 'cal.yaml', dump_calibration('cam', info))
    assert 'binning_x: 2' in path.read_text() and 'do_rectify: true' in path.read_text()
    assert load_calibration(str(path)) == ('cam', info)


def test_the_written_file_looks_like_cameracalibrators():
    text = dump_calibration('usb_camera', make_info())
    keys = [line.split(':')[0] for line in text.splitlines() if not line.startswith(' ')]
    assert keys == ['image_width', 'image_height', 'camera_name', 'camera_matrix',
                    'distortion_model', 'distortion_coefficients', 'rectification_matrix',
                    'projection_matrix']
    assert '  data: [600.0, 0.0, 320.0, 0.0, 600.0, 240.0, 0.0, 0.0, 1.0]\n' in text


finite = st.floats(allow_nan=False, allow_infinity=False)
# Names YAML would read as numbers, booleans or null, or not at all, unless the writer quotes.
names = st.sampled_from(['123', 'yes', 'null', '1e5', 'a: b', '#x', ' x ', "it's"]) | st.text(
    st.characters(blacklist_categories=('Cs',)), min_size=1, max_size=12)


@settings(max_examples=150, deadline=None)
@given(name=names, width=st.integers(1, 8192), height=st.integers(1, 8192),
       k=st.lists(finite, min_size=9, max_size=9), r=st.lists(finite, min_size=9, max_size=9),
       p=st.lists(finite, min_size=12, max_size=12), d=st.lists(finite, max_size=14),
       model=st.sampled_from(['plumb_bob', 'rational_polynomial', 'equidistant', 'my model']))
def test_dump_then_load_gives_back_the_same_calibration(name, width, height, k, r, p, d, model):
    info = CameraInfo(width=width, height=height, distortion_model=model, k=k, r=r, p=p, d=d)
    with tempfile.TemporaryDirectory() as directory:
        path = os.path.join(directory, 'cal.yaml')
        with open(path, 'w') as stream:
            stream.write(dump_calibration(name, info))
        loaded_name, loaded = load_calibration(path)
    assert loaded_name == name
    assert loaded == info
    # Bit for bit, signs of zeros included.
    assert [math.copysign(1, v) for v in loaded.d] == [math.copysign(1, v) for v in info.d]


def replace_line(text, old, new):
    assert old in text
    return text.replace(old, new, 1)


@pytest.mark.parametrize('change, says', [
    (lambda t: '', 'is empty'),
    (lambda t: replace_line(t, 'cols: 5\n', 'cols: [5\n'),
     "line 14: not valid YAML: expected ',' or ']', but got ':' (while parsing a flow "
     'sequence from line 13)'),
    (lambda t: replace_line(t, 'camera_name: usb_camera\n', 'camera_name: usb_camera: x\n'),
     'line 3: not valid YAML'),
    (lambda t: '- ' + t.replace('\n', '\n  '), 'line 1: calibration: expected a mapping'),
    (lambda t: replace_line(t, 'image_height: 480\n', ''), 'missing key image_height'),
    (lambda t: replace_line(t, 'projection_matrix:', 'projection:'),
     'missing key projection_matrix'),
    (lambda t: replace_line(t, '  rows: 1\n', ''),
     'line 12: distortion_coefficients: missing key rows'),
    (lambda t: replace_line(t, 'image_width: 640', 'image_width: 640.5'),
     "line 1: image_width: '640.5' is not an integer"),
    (lambda t: replace_line(t, 'image_width: 640', 'image_width: 0'),
     'line 1: image_width: 0 is out of range'),
    (lambda t: replace_line(t, 'camera_matrix:\n  rows: 3\n  cols: 3',
                            'camera_matrix:\n  rows: 3\n  cols: 4'),
     'line 5: camera_matrix: expected rows: 3, cols: 3, got rows: 3, cols: 4'),
    (lambda t: replace_line(t, '  cols: 5\n', '  cols: 6\n'),
     'line 14: distortion_coefficients.data: 5 numbers for 1 x 6, expected 6'),
    (lambda t: replace_line(t, '1.     ]', '1.     , 0.]'),
     'line 7: camera_matrix.data: 10 numbers for 3 x 3, expected 9'),
    (lambda t: replace_line(t, '611.90524', 'fy'),
     "line 8: camera_matrix.data[4]: 'fy' is not a number"),
    (lambda t: replace_line(t, '-0.235867', 'true'),
     "line 14: distortion_coefficients.data[1]: 'true' is not a number"),
    (lambda t: replace_line(t, '620.04431', '.nan'),
     'line 25: projection_matrix.data[5]: .nan is not a finite number'),
    (lambda t: replace_line(t, '  data: [1., 0., 0.,', '  data: 1\n  x: [1., 0., 0.,'),
     'line 18: rectification_matrix.data: expected a list of numbers'),
])
def test_a_malformed_file_is_named_with_its_line_and_key(tmp_path, change, says):
    path = write(tmp_path / 'bad.yaml', change(CALIBRATOR_YAML))
    with pytest.raises(CalibrationError) as raised:
        load_calibration(str(path))
    message = str(raised.value)
    assert message.startswith(str(path)) and says in message, message
    assert '\n' not in message


def test_a_missing_file_is_named(tmp_path):
    with pytest.raises(CalibrationError, match='nowhere.yaml does not exist'):
        load_calibration(str(tmp_path / 'nowhere.yaml'))


@pytest.mark.parametrize('change, says', [
    ({'width': 0}, 'image size 0x480'),
    ({'fx': 0.0}, 'K has fx = 0'),
    ({'fx': float('nan')}, 'K has a value that is not a finite number'),
    ({'d': [0.1, 0.2, 0.0, 0.0]}, 'plumb_bob takes 5 coefficients, D has 4'),
    ({'model': 'equidistant'}, 'equidistant takes 4 coefficients, D has 5'),
    ({'model': ''}, 'distortion_model is empty'),
])
def test_validate_says_why_a_camera_info_is_no_calibration(change, says):
    assert says in validate_camera_info(make_info(**change))


def test_an_uncalibrated_camera_info_is_no_calibration():
    problem = validate_camera_info(CameraInfo(width=640, height=480))
    assert 'all zeros means uncalibrated' in problem


# --- CameraInfoManager: loading ---

def test_a_calibration_file_is_published_for_its_size(tmp_path, logger):
    path = write(tmp_path / 'cal.yaml', CALIBRATOR_YAML)
    manager = CameraInfoManager('usb_camera', 'file://' + str(path), logger)
    manager.load()
    assert manager.calibrated
    assert_calibration(manager.camera_info(640, 480))
    assert logger.at('warning') == []
    assert logger.at('info') == ['calibration loaded from %s: 640x480 plumb_bob' % path]


def test_the_message_is_built_once_per_calibration_and_size(tmp_path, logger):
    path = write(tmp_path / 'cal.yaml', CALIBRATOR_YAML)
    manager = CameraInfoManager('usb_camera', 'file://' + str(path), logger)
    manager.load()
    assert manager.camera_info(640, 480) is manager.camera_info(640, 480)


def test_the_first_camera_info_loads_when_load_was_not_called(tmp_path, logger):
    path = write(tmp_path / 'cal.yaml', CALIBRATOR_YAML)
    manager = CameraInfoManager('usb_camera', 'file://' + str(path), logger)
    assert_calibration(manager.camera_info(640, 480))
    assert len(logger.at('info')) == 1


def test_no_url_and_no_default_file_is_uncalibrated_with_one_info_line(ros_home, logger):
    manager = CameraInfoManager('usb_camera', '', logger)
    manager.load()
    assert not manager.calibrated
    for _ in range(3):
        assert_uncalibrated(manager.camera_info(640, 480), 640, 480)
    assert logger.at('warning') == []
    default = ros_home / 'camera_info' / 'usb_camera.yaml'
    assert logger.at('info') == [
        'no calibration in %s (camera_info_url is empty): publishing uncalibrated camera_info'
        % default]


def test_no_url_loads_the_default_file(ros_home, logger):
    write(ros_home / 'camera_info' / 'usb_camera.yaml', CALIBRATOR_YAML)
    manager = CameraInfoManager('usb_camera', '', logger)
    manager.load()
    assert_calibration(manager.camera_info(640, 480))


@pytest.mark.parametrize('url, text, says', [
    ('file://{dir}/missing.yaml', None, '{dir}/missing.yaml does not exist'),
    ('file://{dir}/cal.yaml', CALIBRATOR_YAML.replace('cols: 5', 'cols: [5'),
     '{dir}/cal.yaml line 14: not valid YAML'),
    ('file://{dir}/cal.yaml', CALIBRATOR_YAML.replace('image_height: 480\n', ''),
     'missing key image_height'),
    ('file://{dir}/cal.yaml', CALIBRATOR_YAML.replace('612.41893', '0.0'),
     '{dir}/cal.yaml: K has fx = 0'),
    ('ftp://{dir}/cal.yaml', None, 'not a calibration URL'),
    ('package://no_such_package_here/cal.yaml', None, 'is not in the ament index'),
])
def test_bad_calibration_input_is_one_warning_and_uncalibrated(tmp_path, logger, url, text, says):
    if text is not None:
        write(tmp_path / 'cal.yaml', text)
    manager = CameraInfoManager('usb_camera', url.format(dir=tmp_path), logger)
    manager.load()
    assert not manager.calibrated
    assert_uncalibrated(manager.camera_info(640, 480), 640, 480)
    warnings = logger.at('warning')
    assert len(warnings) == 1 and says.format(dir=tmp_path) in warnings[0], warnings
    assert warnings[0].endswith('publishing uncalibrated camera_info')


def test_a_calibration_for_another_camera_is_used_with_one_warning(tmp_path, logger):
    path = write(tmp_path / 'cal.yaml', CALIBRATOR_YAML.replace('usb_camera', 'narrow_stereo'))
    manager = CameraInfoManager('usb_camera', 'file://' + str(path), logger)
    manager.load()
    assert manager.calibrated
    assert_calibration(manager.camera_info(640, 480))
    assert logger.at('warning') == [
        "%s is the calibration of camera 'narrow_stereo', not 'usb_camera': using it anyway"
        % path]


def test_a_calibration_for_another_resolution_is_one_warning_and_uncalibrated(tmp_path, logger):
    path = write(tmp_path / 'cal.yaml', CALIBRATOR_YAML)
    manager = CameraInfoManager('usb_camera', 'file://' + str(path), logger)
    manager.load()
    for _ in range(5):
        assert_uncalibrated(manager.camera_info(1280, 720), 1280, 720)
    assert logger.at('warning') == [
        'the calibration from %s is for 640x480 but the images are 1280x720: publishing '
        'uncalibrated camera_info; calibrate at this size' % path]
    assert manager.calibrated
    assert_calibration(manager.camera_info(640, 480))


# --- CameraInfoManager: set_camera_info ---

def test_set_camera_info_without_url_writes_the_default_file(ros_home, logger):
    manager = CameraInfoManager('usb_camera', '', logger)
    manager.load()
    info = make_info(fx=555.5)
    success, status = manager.set_camera_info(info)
    default = ros_home / 'camera_info' / 'usb_camera.yaml'
    assert success, status
    assert status == 'calibration stored in %s and published from the next frame on' % default
    assert load_calibration(str(default)) == ('usb_camera', info)
    assert manager.calibrated and manager.camera_info(640, 480) == info
    restarted = CameraInfoManager('usb_camera', '', RecordingLogger())
    restarted.load()
    assert restarted.camera_info(640, 480) == info


def test_set_camera_info_creates_the_directories_of_a_file_url(tmp_path, logger):
    url = 'file://%s/a/b/c/${NAME}.yaml' % tmp_path
    manager = CameraInfoManager('front', url, logger)
    assert manager.set_camera_info(make_info())[0]
    assert load_calibration(str(tmp_path / 'a' / 'b' / 'c' / 'front.yaml'))[0] == 'front'
    assert oct((tmp_path / 'a' / 'b' / 'c' / 'front.yaml').stat().st_mode & 0o777) == '0o644'


def test_set_camera_info_replaces_the_previous_file(tmp_path, logger):
    path = write(tmp_path / 'cal.yaml', CALIBRATOR_YAML)
    manager = CameraInfoManager('usb_camera', 'file://' + str(path), logger)
    manager.load()
    assert manager.set_camera_info(make_info(fx=777.0))[0]
    assert load_calibration(str(path))[1].k[0] == 777.0
    assert os.listdir(tmp_path) == ['cal.yaml']


def test_set_camera_info_refuses_a_package_url(logger):
    url = 'package://py_vision/config/example_calibration.yaml'
    manager = CameraInfoManager('usb_camera', url, logger)
    manager.load()
    before = os.path.getmtime(resolve_url(url, 'usb_camera'))
    success, status = manager.set_camera_info(make_info(fx=123.0))
    assert not success
    assert status.startswith('calibration not stored: camera_info_url %s points into an '
                             'installed package, which a rebuild overwrites' % url)
    assert os.path.getmtime(resolve_url(url, 'usb_camera')) == before
    assert manager.camera_info(640, 480).k[0] != 123.0


@pytest.mark.parametrize('url, says', [
    ('ftp://host/cal.yaml', 'camera_info_url is unusable: ftp://host/cal.yaml: not a calibration'),
    ('file:///x/${FOO}.yaml', 'unknown substitution ${FOO}'),
])
def test_set_camera_info_refuses_an_unusable_url(logger, ros_home, url, says):
    manager = CameraInfoManager('usb_camera', url, logger)
    success, status = manager.set_camera_info(make_info())
    assert not success and says in status
    assert not manager.calibrated and not ros_home.exists()


def test_set_camera_info_refuses_what_is_no_calibration(tmp_path, logger):
    manager = CameraInfoManager('usb_camera', 'file://%s/cal.yaml' % tmp_path, logger)
    success, status = manager.set_camera_info(make_info(fx=0.0))
    assert not success
    assert status.startswith('calibration refused: K has fx = 0')
    assert os.listdir(tmp_path) == [] and not manager.calibrated


def test_a_failed_write_leaves_the_old_file_and_calibration(tmp_path, logger, monkeypatch):
    path = write(tmp_path / 'cal.yaml', CALIBRATOR_YAML)
    manager = CameraInfoManager('usb_camera', 'file://' + str(path), logger)
    manager.load()

    def disk_error(descriptor):
        raise OSError(errno.EIO, os.strerror(errno.EIO))
    monkeypatch.setattr(calibration.os, 'fsync', disk_error)
    success, status = manager.set_camera_info(make_info(fx=999.0))
    monkeypatch.undo()
    assert not success
    assert status == 'calibration not stored in %s: %s' % (path, os.strerror(errno.EIO))
    assert path.read_text() == CALIBRATOR_YAML
    assert os.listdir(tmp_path) == ['cal.yaml']
    assert_calibration(manager.camera_info(640, 480))


def test_a_directory_that_cannot_be_made_is_reported(tmp_path, logger):
    write(tmp_path / 'taken', 'a file where a directory should be')
    manager = CameraInfoManager('usb_camera', 'file://%s/taken/cal.yaml' % tmp_path, logger)
    success, status = manager.set_camera_info(make_info())
    assert not success
    assert 'cannot create directory %s/taken' % tmp_path in status
    assert not manager.calibrated


def test_camera_info_is_never_half_old_half_new_while_set_camera_info_runs(tmp_path, logger):
    manager = CameraInfoManager('usb_camera', 'file://%s/cal.yaml' % tmp_path, logger)
    calibrations = [make_info(fx=500.0, d=[0.1, 0.2, 0.3, 0.4, 0.5]),
                    make_info(fx=700.0, d=[-0.1, -0.2, -0.3, -0.4, -0.5])]
    consistent = {(info.k[0], info.d[0], info.p[0]) for info in calibrations}
    assert manager.set_camera_info(calibrations[0])[0]
    seen = []
    stop = threading.Event()

    def capture():
        while not stop.is_set():
            info = manager.camera_info(640, 480)
            seen.append((info.k[0], info.d[0], info.p[0]))

    thread = threading.Thread(target=capture)
    thread.start()
    try:
        for index in range(100):
            new = calibrations[index % 2]
            assert manager.set_camera_info(new) == (
                True, 'calibration stored in %s/cal.yaml and published from the next frame on'
                % tmp_path)
            assert manager.camera_info(640, 480) == new  # the next frame has it
    finally:
        stop.set()
        thread.join(timeout=30)
    assert not thread.is_alive()
    assert seen and set(seen) <= consistent, set(seen) - consistent


# What is no calibration file at all: each is one CalibrationError, at once (issue 28).

def read_in_time(path, seconds=10.0):
    """Return what load_calibration(path) raised, failing when it takes longer than seconds."""
    outcome = []

    def read():
        try:
            load_calibration(path)
            outcome.append(None)
        except Exception as error:  # noqa: B902 - what it raised is the result
            outcome.append(error)
    reader = threading.Thread(target=read, daemon=True)
    reader.start()
    reader.join(seconds)
    assert outcome, 'reading %s did not end within %g s' % (path, seconds)
    return outcome[0]


@pytest.mark.parametrize('path, says', [
    ('/dev/zero', 'not a regular file (a character device)'),
    ('/dev/urandom', 'not a regular file (a character device)'),
    ('/', 'not a regular file (a directory)'),
])
def test_a_device_or_directory_is_refused_by_its_type(path, says):
    error = read_in_time(path)
    assert isinstance(error, CalibrationError) and says in str(error), error


def test_a_fifo_is_refused_without_waiting_for_a_writer(tmp_path):
    fifo = tmp_path / 'calibration.yaml'
    os.mkfifo(fifo)
    error = read_in_time(str(fifo))
    assert isinstance(error, CalibrationError) and 'a FIFO' in str(error), error


def test_a_file_over_the_limit_is_refused_unread(tmp_path):
    big = tmp_path / 'big.yaml'
    with open(big, 'wb') as stream:
        stream.truncate(calibration.MAX_FILE_BYTES + 1)   # sparse: no disk used
    error = read_in_time(str(big))
    assert isinstance(error, CalibrationError) and 'over 1048576 bytes' in str(error), error


@pytest.mark.parametrize('text', ['[' * 1000, 'a: ' + '{b: ' * 1000, '- ' * 2000 + 'x'])
def test_yaml_nested_too_deep_is_refused(tmp_path, text):
    path = tmp_path / 'deep.yaml'
    path.write_text(text)
    error = read_in_time(str(path))
    assert isinstance(error, CalibrationError) and str(path) in str(error), error


def test_a_device_url_is_one_warning_and_uncalibrated(logger):
    manager = CameraInfoManager('cam', 'file:///dev/zero', logger)
    manager.load()
    assert not manager.calibrated
    warnings = logger.at('warning')
    assert len(warnings) == 1 and '/dev/zero' in warnings[0], warnings
