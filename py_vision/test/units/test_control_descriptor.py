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

"""The camera-control descriptor words: what control_params writes, camera_panel reads back."""

from py_vision.capture.controls import CID, ControlInfo, INT, MENU
from py_vision.control_descriptor import parse_constraints, parse_menu
from py_vision.control_names import USB_CAM_ALIASES
from py_vision.control_params import alias_spec, control_spec

KINDS = ('bool', 'integer', 'double', 'string')
EXPOSURE_MODES = ((1, 'Manual Mode'), (3, 'Aperture Priority Mode'))


def test_a_menu_control_reads_back_its_entries_and_activity():
    control = ControlInfo(CID.EXPOSURE_AUTO, 'Auto Exposure', MENU, 0, 3, 1, 3, 3,
                          menu=EXPOSURE_MODES, inactive=True)
    spec = control_spec(control, 'auto_exposure', 'a test holds it')
    assert parse_menu(spec.description) == [
        {'value': 1, 'label': 'Manual Mode'}, {'value': 3, 'label': 'Aperture Priority Mode'}]
    words = parse_constraints(spec.constraints, KINDS)
    assert (words.alias_of, words.inactive) == (None, 'while a test holds it')


def test_an_active_control_reads_back_active_with_its_type_and_no_menu():
    control = ControlInfo(CID.BRIGHTNESS, 'Brightness', INT, -64, 64, 1, 0, 5, read_only=True)
    spec = control_spec(control, 'brightness')
    assert parse_menu(spec.description) is None
    words = parse_constraints(spec.constraints, KINDS)
    assert (words.kind, words.alias_of, words.inactive) == ('integer', None, None)


def test_an_inactive_control_without_a_known_holder_says_the_cameras_mode_holds_it():
    control = ControlInfo(CID.EXPOSURE_ABSOLUTE, 'Exposure Time, Absolute', INT, 3, 2047,
                          inactive=True)
    spec = control_spec(control, 'exposure_time_absolute', '')
    assert parse_constraints(spec.constraints, KINDS).inactive == \
        "while the camera's current mode holds it"


def test_a_usb_cam_name_reads_back_the_control_it_stands_for():
    control = ControlInfo(CID.BRIGHTNESS, 'Brightness', INT, -64, 64)
    spec = alias_spec(USB_CAM_ALIASES['brightness'], control, 'brightness')
    assert parse_constraints(spec.constraints, KINDS).alias_of == 'brightness'
    assert parse_constraints('not a camera control', KINDS) is None
