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
Camera calibration the way camera_info_manager keeps it, in Python.

ROS's camera_info_manager and camera_calibration_parsers are C++ and not on PyPI; this module
does their job for py_vision's publisher: it resolves `camera_info_url`, reads and writes the
YAML that camera_calibration's cameracalibrator produces, and hands out the `CameraInfo` to
publish beside each image. It knows nothing of nodes: the publisher owns the topic and the
`set_camera_info` service and calls `CameraInfoManager`.

URLs (as camera_info_manager): `file:///abs/path.yaml`, `package://<pkg>/<path>` (the package's
share directory from the ament index) and the empty URL, which means
`file://${ROS_HOME}/camera_info/${NAME}.yaml` (`ROS_HOME` defaults to `~/.ros`). `${NAME}` is
the camera name and `${ROS_HOME}` that directory; any other `${...}` makes the URL unusable.
Scheme names are case-insensitive.

What happens with each kind of input (camera_info_manager's choice unless said otherwise):
- Empty URL and no file at the default path: uncalibrated, one info line (the usual case of a
  camera that was never calibrated).
- A URL that cannot be used (unknown scheme, relative file path, unknown package), a missing
  file, malformed YAML, a missing or wrong-sized matrix, non-numeric data, or values that
  `validate_camera_info` rejects: one warning naming the file and the key or line, uncalibrated.
  So is what is no calibration file at all: anything but a regular file (a FIFO, a device such
  as /dev/zero, a directory: refused by its type, before it is opened, so that reading never
  waits), a file over MAX_FILE_BYTES (1 MiB; cameracalibrator writes about 1 KB), or YAML nested
  deeper than the parser's recursion allows.
- A file for another camera name: one warning, and the calibration is used all the same.
- A calibration for another resolution than the camera delivers: one warning, and the
  published CameraInfo is uncalibrated for the delivered size (what camera1394 and
  camera_aravis do), because K and P scaled to another size would mislead image_proc.
- `set_camera_info` with an empty URL writes the default file above, which the empty URL also
  loads from, so the calibration is there again after a restart. A `package://` URL is refused
  (camera_info_manager would write into the installed share directory, which the next build
  overwrites and which is read-only on the boards), and so is an unusable URL (camera_info_
  manager would write to the default file, which this URL never reads back). A CameraInfo
  that `validate_camera_info` rejects is refused too. The file is written atomically, and the
  new calibration is published only once it is stored (camera_info_manager adopts it even when
  the write fails; here what is published is always what the file holds).
- A file without `camera_name` is taken as camera `unknown`; without `distortion_model`, the
  model is `plumb_bob` for up to 5 coefficients and `rational_polynomial` above, as
  cameracalibrator decides. `binning_x`, `binning_y` and `roi` are read when present and
  written only when they differ from the defaults, so the file looks like cameracalibrator's.
"""

import copy
import math
import os
import re
import stat
import tempfile
import threading
from typing import Protocol

from ament_index_python.packages import get_package_share_directory, PackageNotFoundError
from sensor_msgs.msg import CameraInfo
import yaml

DEFAULT_URL = 'file://${ROS_HOME}/camera_info/${NAME}.yaml'
# The largest calibration file read: cameracalibrator's are about 1 KB.
MAX_FILE_BYTES = 1 << 20

# Number of distortion coefficients each well-known model takes (sensor_msgs'
# distortion_models); other model names are passed through with any count.
MODEL_COEFFICIENTS = {'plumb_bob': 5, 'rational_polynomial': 8, 'equidistant': 4}

# (YAML key, CameraInfo field, rows, cols) of the fixed-size matrices.
_MATRICES = (
    ('camera_matrix', 'k', 3, 3),
    ('rectification_matrix', 'r', 3, 3),
    ('projection_matrix', 'p', 3, 4),
)
_ROI_KEYS = ('x_offset', 'y_offset', 'height', 'width')
_CAMERA_NAME = re.compile(r'[A-Za-z0-9_]+\Z')
_SUBSTITUTION = re.compile(r'\$\{([^}]*)\}')
_INT_TAG = 'tag:yaml.org,2002:int'
_FLOAT_TAG = 'tag:yaml.org,2002:float'
_BOOL_TAG = 'tag:yaml.org,2002:bool'


class CalibrationError(Exception):
    """A calibration URL, file or message that cannot be used; the message says why in a line."""


class Logger(Protocol):
    """What CameraInfoManager logs through (an rclpy logger fits)."""

    def info(self, message: str) -> None:
        """Log an info line."""

    def warning(self, message: str) -> None:
        """Log a warning line."""


def is_valid_camera_name(camera_name: str) -> bool:
    """Whether camera_name is as camera_info_manager accepts it: letters, digits and _ only."""
    # The name becomes part of a file name through ${NAME}, so no '/' or '..'.
    return bool(_CAMERA_NAME.match(camera_name))


def _check_camera_name(camera_name: str) -> None:
    if not is_valid_camera_name(camera_name):
        raise CalibrationError(
            'camera name %r is not usable: it must be letters, digits and _ only' % camera_name)


def _ros_home() -> str:
    return os.environ.get('ROS_HOME') or os.path.join(os.path.expanduser('~'), '.ros')


def resolve_url(url: str, camera_name: str) -> str:
    """
    Return the file a calibration URL names, with ${NAME} and ${ROS_HOME} substituted.

    An empty URL means DEFAULT_URL. Raise CalibrationError if the URL cannot be used.
    """
    url = url or DEFAULT_URL

    def substitute(match):
        variable = match.group(1)
        if variable == 'NAME':
            _check_camera_name(camera_name)
            return camera_name
        if variable == 'ROS_HOME':
            return _ros_home()
        raise CalibrationError('%s: unknown substitution ${%s} (only ${NAME} and ${ROS_HOME})'
                               % (url, variable))

    resolved = _SUBSTITUTION.sub(substitute, url)
    scheme, _, rest = resolved.partition('://')
    scheme = scheme.lower()
    if scheme == 'file' and rest.startswith('/'):
        return rest
    if scheme == 'file':
        raise CalibrationError('%s: a file URL needs an absolute path: file:///abs/path.yaml'
                               % url)
    if scheme == 'package':
        package, _, path = rest.partition('/')
        if not package or not path:
            raise CalibrationError('%s: expected package://<package>/<path>' % url)
        try:
            return os.path.join(get_package_share_directory(package), path)
        except PackageNotFoundError:
            raise CalibrationError('%s: package %r is not in the ament index (AMENT_PREFIX_PATH)'
                                   % (url, package)) from None
    raise CalibrationError('%s: not a calibration URL; use file:///abs/path.yaml, '
                           'package://<package>/<path>, or empty for %s' % (url, DEFAULT_URL))


class _Document:
    """A composed YAML document read with error messages naming the file, line and key."""

    def __init__(self, text: str, source: str):
        self.source = source
        try:
            self.root = yaml.compose(text, Loader=yaml.SafeLoader)
        except yaml.MarkedYAMLError as error:
            mark, context = error.problem_mark or error.context_mark, error.context_mark
            message = '%s%s: not valid YAML: %s' % (
                source, ' line %d' % (mark.line + 1) if mark else '', error.problem)
            if context is not None and context.line != mark.line:
                message += ' (%s from line %d)' % (error.context, context.line + 1)
            raise CalibrationError(message) from None
        except yaml.YAMLError as error:
            raise CalibrationError('%s: not valid YAML: %s' % (source, error)) from None
        except RecursionError:
            raise CalibrationError('%s: not a calibration: its YAML nests too deep' % source
                                   ) from None
        if self.root is None:
            raise CalibrationError('%s is empty: expected a calibration (image_width, '
                                   'image_height, camera_matrix, ...)' % source)
        self._constructor = yaml.SafeLoader('')

    def error(self, node: yaml.Node, key: str, problem: str) -> CalibrationError:
        return CalibrationError('%s line %d: %s: %s' % (
            self.source, node.start_mark.line + 1, key, problem))

    def mapping(self, node: yaml.Node, key: str) -> dict:
        if not isinstance(node, yaml.MappingNode):
            raise self.error(node, key, 'expected a mapping of keys')
        return {k.value: v for k, v in node.value if isinstance(k, yaml.ScalarNode)}

    def require(self, mapping: dict, key: str, parent: yaml.Node, where: str = '') -> yaml.Node:
        if key in mapping:
            return mapping[key]
        if where:
            raise self.error(parent, where, 'missing key %s' % key)
        raise CalibrationError('%s: missing key %s' % (self.source, key))

    def integer(self, node: yaml.Node, key: str, minimum: int) -> int:
        if not isinstance(node, yaml.ScalarNode) or node.tag != _INT_TAG:
            raise self.error(node, key, '%s is not an integer' % _show(node))
        value = self._constructor.construct_object(node)
        if value < minimum:
            raise self.error(node, key, '%d is out of range (at least %d)' % (value, minimum))
        return value

    def number(self, node: yaml.Node, key: str) -> float:
        if not isinstance(node, yaml.ScalarNode) or node.tag not in (_INT_TAG, _FLOAT_TAG):
            raise self.error(node, key, '%s is not a number' % _show(node))
        value = float(self._constructor.construct_object(node))
        if not math.isfinite(value):
            raise self.error(node, key, '%s is not a finite number' % node.value)
        return value

    def boolean(self, node: yaml.Node, key: str) -> bool:
        if not isinstance(node, yaml.ScalarNode) or node.tag != _BOOL_TAG:
            raise self.error(node, key, '%s is not true or false' % _show(node))
        return self._constructor.construct_object(node)

    def text(self, node: yaml.Node, key: str) -> str:
        if not isinstance(node, yaml.ScalarNode):
            raise self.error(node, key, 'expected a string')
        return node.value

    def matrix(self, node: yaml.Node, key: str, rows: int = 0, cols: int = 0) -> list:
        """Read a rows/cols/data matrix; rows and cols 0 mean any shape."""
        fields = self.mapping(node, key)
        got_rows = self.integer(self.require(fields, 'rows', node, key), key + '.rows', 0)
        got_cols = self.integer(self.require(fields, 'cols', node, key), key + '.cols', 0)
        if rows and (got_rows, got_cols) != (rows, cols):
            raise self.error(node, key, 'expected rows: %d, cols: %d, got rows: %d, cols: %d'
                             % (rows, cols, got_rows, got_cols))
        data = self.require(fields, 'data', node, key)
        if not isinstance(data, yaml.SequenceNode):
            raise self.error(data, key + '.data', 'expected a list of numbers')
        if len(data.value) != got_rows * got_cols:
            raise self.error(data, key + '.data', '%d numbers for %d x %d, expected %d' % (
                len(data.value), got_rows, got_cols, got_rows * got_cols))
        return [self.number(item, '%s.data[%d]' % (key, index))
                for index, item in enumerate(data.value)]


def _show(node: yaml.Node) -> str:
    return repr(node.value) if isinstance(node, yaml.ScalarNode) else 'a ' + node.id


def _kind(mode: int) -> str:
    for test, kind in ((stat.S_ISDIR, 'a directory'), (stat.S_ISFIFO, 'a FIFO'),
                       (stat.S_ISCHR, 'a character device'), (stat.S_ISBLK, 'a block device'),
                       (stat.S_ISSOCK, 'a socket')):
        if test(mode):
            return kind
    return 'not a file'


def _read_file(path: str) -> str:
    """Return the text of the calibration file path; CalibrationError if it is not one."""
    def refuse(mode):
        return CalibrationError('%s is not a regular file (%s): not a calibration' % (
            path, _kind(mode)))
    try:
        # By its type first: opening a FIFO waits for a writer, reading a device never ends.
        mode = os.stat(path).st_mode
        if not stat.S_ISREG(mode):
            raise refuse(mode)
        # Non-blocking, in case a FIFO took the file's place since.
        descriptor = os.open(path, os.O_RDONLY | os.O_NONBLOCK | os.O_NOCTTY)
        with os.fdopen(descriptor, 'rb') as stream:
            mode = os.fstat(stream.fileno()).st_mode
            if not stat.S_ISREG(mode):
                raise refuse(mode)
            data = stream.read(MAX_FILE_BYTES + 1)
    except FileNotFoundError:
        raise CalibrationError('%s does not exist' % path) from None
    except OSError as error:
        raise CalibrationError('cannot read %s: %s' % (path, error.strerror or error)) from None
    if len(data) > MAX_FILE_BYTES:
        raise CalibrationError('%s is over %d bytes: not a calibration' % (path, MAX_FILE_BYTES))
    try:
        return data.decode('utf-8')
    except UnicodeDecodeError as error:
        raise CalibrationError('cannot read %s: %s' % (path, error)) from None


def load_calibration(path: str) -> tuple[str, CameraInfo]:
    """
    Read a camera_calibration YAML file: return (camera name in the file, CameraInfo).

    Raise CalibrationError naming the file and the line or key for a missing or malformed file.
    """
    doc = _Document(_read_file(path), path)
    fields = doc.mapping(doc.root, 'calibration')
    info = CameraInfo()
    info.width = doc.integer(doc.require(fields, 'image_width', doc.root), 'image_width', 1)
    info.height = doc.integer(doc.require(fields, 'image_height', doc.root), 'image_height', 1)
    for key, field, rows, cols in _MATRICES:
        setattr(info, field, doc.matrix(doc.require(fields, key, doc.root), key, rows, cols))
    key = 'distortion_coefficients'
    info.d = doc.matrix(doc.require(fields, key, doc.root), key)
    if 'distortion_model' in fields:
        info.distortion_model = doc.text(fields['distortion_model'], 'distortion_model')
    else:
        info.distortion_model = 'plumb_bob' if len(info.d) <= 5 else 'rational_polynomial'
    for key in ('binning_x', 'binning_y'):
        if key in fields:
            setattr(info, key, doc.integer(fields[key], key, 0))
    if 'roi' in fields:
        roi = doc.mapping(fields['roi'], 'roi')
        for key in _ROI_KEYS:
            setattr(info.roi, key,
                    doc.integer(doc.require(roi, key, fields['roi'], 'roi'), 'roi.' + key, 0))
        info.roi.do_rectify = doc.boolean(
            doc.require(roi, 'do_rectify', fields['roi'], 'roi'), 'roi.do_rectify')
    name = doc.text(fields['camera_name'], 'camera_name') if 'camera_name' in fields else 'unknown'
    return name, info


def _matrix_yaml(values, rows: int, cols: int) -> dict:
    return {'rows': rows, 'cols': cols, 'data': [float(value) for value in values]}


def dump_calibration(camera_name: str, info: CameraInfo) -> str:
    """Return the YAML cameracalibrator writes for info; load_calibration reads it back equal."""
    document = {
        'image_width': int(info.width),
        'image_height': int(info.height),
        'camera_name': camera_name,
        'camera_matrix': _matrix_yaml(info.k, 3, 3),
        'distortion_model': info.distortion_model,
        'distortion_coefficients': _matrix_yaml(info.d, 1, len(info.d)),
        'rectification_matrix': _matrix_yaml(info.r, 3, 3),
        'projection_matrix': _matrix_yaml(info.p, 3, 4),
    }
    if info.binning_x or info.binning_y:
        document['binning_x'] = int(info.binning_x)
        document['binning_y'] = int(info.binning_y)
    roi = info.roi
    if any(getattr(roi, key) for key in _ROI_KEYS) or roi.do_rectify:
        document['roi'] = {key: int(getattr(roi, key)) for key in _ROI_KEYS}
        document['roi']['do_rectify'] = bool(roi.do_rectify)
    # PyYAML writes floats with repr() (exact) and a '.' that YAML 1.1 needs to read them back
    # as floats; flow style for the number lists and one line each, as cameracalibrator.
    return yaml.safe_dump(document, sort_keys=False, default_flow_style=None, width=1 << 30)


def validate_camera_info(info: CameraInfo) -> str | None:
    """Return why info cannot be stored or used as a calibration, or None if it can."""
    if info.width < 1 or info.height < 1:
        return 'image size %dx%d: width and height must be positive' % (info.width, info.height)
    for name, values in (('K', info.k), ('D', info.d), ('R', info.r), ('P', info.p)):
        if not all(math.isfinite(value) for value in values):
            return '%s has a value that is not a finite number' % name
    if info.k[0] <= 0 or info.k[4] <= 0:
        return ('K has fx = %g, fy = %g: both must be positive (all zeros means uncalibrated)'
                % (info.k[0], info.k[4]))
    if info.p[0] <= 0 or info.p[5] <= 0:
        return 'P has fx = %g, fy = %g: both must be positive' % (info.p[0], info.p[5])
    expected = MODEL_COEFFICIENTS.get(info.distortion_model)
    if expected is not None and len(info.d) != expected:
        return 'distortion model %s takes %d coefficients, D has %d' % (
            info.distortion_model, expected, len(info.d))
    if not info.distortion_model and len(info.d):
        return 'D has %d coefficients but distortion_model is empty' % len(info.d)
    return None


def _write_atomically(path: str, text: str) -> None:
    """Replace path by a file holding text: readers see the old file or the new, never part."""
    directory = os.path.dirname(path)
    try:
        os.makedirs(directory, exist_ok=True)
    except OSError as error:
        raise OSError('cannot create directory %s: %s' % (directory, error.strerror)) from None
    handle, temporary = tempfile.mkstemp(
        dir=directory, prefix='.%s.' % os.path.basename(path), suffix='.tmp')
    try:
        with os.fdopen(handle, 'w', encoding='utf-8') as stream:
            stream.write(text)
            stream.flush()
            os.fsync(stream.fileno())
        os.chmod(temporary, 0o644)  # mkstemp makes it 0600; calibrations are not secret
        os.replace(temporary, path)
    except BaseException:
        os.unlink(temporary)
        raise
    # The rename survives a power loss (a board keeps the old file or the new) once the
    # directory is synced too; some file systems cannot, and the file is in place either way.
    try:
        descriptor = os.open(directory, os.O_RDONLY)
        try:
            os.fsync(descriptor)
        finally:
            os.close(descriptor)
    except OSError:
        pass


class CameraInfoManager:
    """
    The calibration of one camera: loaded from camera_info_url, stored by set_camera_info.

    camera_info() is called by the capture thread for every frame and set_camera_info() by the
    service: the messages it hands out are built once per calibration and image size, and are
    replaced, never changed, when the calibration changes.
    """

    def __init__(self, camera_name: str, url: str, logger: Logger):
        """Raise CalibrationError for a camera name camera_info_manager would not accept."""
        _check_camera_name(camera_name)
        self._camera_name = camera_name
        self._url = url
        self._logger = logger
        self._store_lock = threading.Lock()  # one load or store at a time, file I/O included
        self._lock = threading.Lock()  # the adopted calibration and its cache, never held on I/O
        self._calibration: CameraInfo | None = None
        self._source = ''
        self._cache: dict[tuple[int, int], CameraInfo] = {}
        self._loaded = False

    @property
    def calibrated(self) -> bool:
        """Whether a calibration is loaded or stored (whatever resolution it is for)."""
        with self._lock:
            return self._calibration is not None

    def load(self) -> None:
        """Read the calibration from the URL; never raises: logs why it stays uncalibrated."""
        with self._store_lock:
            self._adopt(*self._read())

    def _read(self) -> tuple[CameraInfo | None, str]:
        uncalibrated = 'publishing uncalibrated camera_info'
        try:
            path = resolve_url(self._url, self._camera_name)
        except CalibrationError as error:
            self._logger.warning('camera_info_url is unusable: %s; %s' % (error, uncalibrated))
            return None, ''
        if not self._url and not os.path.exists(path):
            self._logger.info('no calibration in %s (camera_info_url is empty): %s'
                              % (path, uncalibrated))
            return None, ''
        try:
            name, info = load_calibration(path)
        except CalibrationError as error:
            self._logger.warning('calibration not loaded: %s; %s' % (error, uncalibrated))
            return None, ''
        problem = validate_camera_info(info)
        if problem is not None:
            self._logger.warning('calibration not loaded: %s: %s; %s' % (
                path, problem, uncalibrated))
            return None, ''
        if name != self._camera_name:
            self._logger.warning('%s is the calibration of camera %r, not %r: using it anyway'
                                 % (path, name, self._camera_name))
        self._logger.info('calibration loaded from %s: %dx%d %s' % (
            path, info.width, info.height, info.distortion_model))
        return info, path

    def _adopt(self, info: CameraInfo | None, source: str) -> None:
        with self._lock:
            self._calibration = copy.deepcopy(info)
            self._source = source
            self._cache = {}
            self._loaded = True

    def camera_info(self, width: int, height: int) -> CameraInfo:
        """
        Return the CameraInfo to publish with an image of this size (loads on first call).

        The message is shared between calls: set its header and publish it, from one thread.
        """
        if not self._loaded:
            with self._store_lock:
                if not self._loaded:
                    self._adopt(*self._read())
        with self._lock:
            info = self._cache.get((width, height))
            if info is None:
                info = self._build(width, height)
                self._cache[(width, height)] = info
            return info

    def _build(self, width: int, height: int) -> CameraInfo:
        calibration = self._calibration
        if calibration is not None and (calibration.width, calibration.height) == (width, height):
            return copy.deepcopy(calibration)
        if calibration is not None:
            # Once per calibration and size: the result is cached.
            self._logger.warning(
                'the calibration from %s is for %dx%d but the images are %dx%d: publishing '
                'uncalibrated camera_info; calibrate at this size' % (
                    self._source, calibration.width, calibration.height, width, height))
        return CameraInfo(width=width, height=height)

    def set_camera_info(self, info: CameraInfo) -> tuple[bool, str]:
        """
        Validate info, store it in the URL's file and publish it from the next frame on.

        Return (success, status message) for the service response and the caller's log; on
        failure the message says why and nothing changed.
        """
        with self._store_lock:
            return self._store(info)

    def _store(self, info: CameraInfo) -> tuple[bool, str]:
        problem = validate_camera_info(info)
        if problem is not None:
            return False, 'calibration refused: %s' % problem
        if self._url.partition('://')[0].lower() == 'package':
            return False, (
                'calibration not stored: camera_info_url %s points into an installed package, '
                'which a rebuild overwrites; use a file:/// URL, or an empty URL for %s'
                % (self._url, DEFAULT_URL))
        try:
            path = resolve_url(self._url, self._camera_name)
        except CalibrationError as error:
            return False, 'calibration not stored: camera_info_url is unusable: %s' % error
        try:
            _write_atomically(path, dump_calibration(self._camera_name, info))
        except OSError as error:
            return False, 'calibration not stored in %s: %s' % (
                path, error.strerror or error)
        self._adopt(info, path)
        return True, 'calibration stored in %s and published from the next frame on' % path
