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
Use the Fast DDS profile shipped with py_vision unless the user chose their own.

Fast DDS' default shared-memory segment (0.5 MB) is smaller than one VGA frame, so images
fall back to fragmented UDP and best-effort subscribers lose many of them. The packaged
profile (config/fastdds_image_profile.xml) gives shared memory room for frames and enlarges the
UDP socket buffers for other hosts.

Fast DDS drops its whole UDP transport, silently, when a socket buffer larger than the
kernel allows (net.core.wmem_max / rmem_max) is requested, and with it every peer on another
host. So the buffer sizes are capped at the limits of the machine (and network namespace) the
node starts on, in a copy of the profile written to the temporary directory.
"""

import hashlib
import os
import re
import tempfile

from ament_index_python.packages import get_package_share_directory, PackageNotFoundError

PROFILE_NAME = 'fastdds_image_profile.xml'
_USER_SETTINGS = ('FASTRTPS_DEFAULT_PROFILES_FILE', 'FASTDDS_DEFAULT_PROFILES_FILE')
_FAST_DDS_RMWS = ('', 'rmw_fastrtps_cpp', 'rmw_fastrtps_dynamic_cpp')
_KERNEL_LIMITS = {
    'sendBufferSize': '/proc/sys/net/core/wmem_max',
    'receiveBufferSize': '/proc/sys/net/core/rmem_max',
}


def packaged_profile():
    """Return the installed profile's path, or None when the package is not installed."""
    try:
        share = get_package_share_directory('py_vision')
    except (PackageNotFoundError, OSError):
        # Not found through AMENT_PREFIX_PATH (install/setup.bash not sourced): look where
        # colcon installs it relative to this module, <prefix>/lib/pythonX.Y/site-packages.
        share = os.path.join(os.path.dirname(os.path.abspath(__file__)),
                             '..', '..', '..', '..', 'share', 'py_vision')
    path = os.path.normpath(os.path.join(share, 'config', PROFILE_NAME))
    return path if os.path.isfile(path) else None


def _kernel_limit(path):
    try:
        with open(path) as limit:
            return int(limit.read())
    except (OSError, ValueError):
        return None


def fit_to_kernel(profile, limits=None):
    """
    Return the path of a profile whose socket buffers the kernel accepts.

    That is profile itself when its buffer sizes are within the limits (by default read from
    /proc/sys/net/core), else a capped copy in the temporary directory.
    """
    if limits is None:
        limits = {tag: _kernel_limit(path) for tag, path in _KERNEL_LIMITS.items()}
    with open(profile) as source:
        text = source.read()

    def cap(match):
        limit = limits.get(match.group(1))
        size = int(match.group(2))
        if limit is not None and size > limit:
            size = limit
        return '<%s>%d</%s>' % (match.group(1), size, match.group(1))
    fitted = re.sub(r'<(sendBufferSize|receiveBufferSize)>(\d+)</\1>', cap, text)
    if fitted == text:
        return profile
    # Named after its content, so an upgraded profile never meets a stale copy; a file of
    # another user's is never trusted.
    digest = hashlib.sha256(fitted.encode()).hexdigest()[:16]
    path = os.path.join(tempfile.gettempdir(), 'py_vision_fastdds_%d_%s.xml' % (
        os.getuid(), digest))
    if not (os.path.isfile(path) and os.stat(path).st_uid == os.getuid()):
        handle, partial = tempfile.mkstemp(dir=os.path.dirname(path), suffix='.xml')
        with os.fdopen(handle, 'w') as out:
            out.write(fitted)
        os.chmod(partial, 0o644)
        os.replace(partial, path)
    return path


def use_packaged_profile(environ=os.environ):
    """
    Point Fast DDS at the packaged profile; return the path used, or None if left alone.

    Left alone: another RMW is selected, the user set a profile file, or Fast DDS would
    load DEFAULT_FASTRTPS_PROFILES.xml from the working directory.
    """
    if environ.get('RMW_IMPLEMENTATION', '') not in _FAST_DDS_RMWS:
        return None
    if any(environ.get(name) for name in _USER_SETTINGS):
        return None
    if os.path.exists('DEFAULT_FASTRTPS_PROFILES.xml'):
        return None
    path = packaged_profile()
    if path is not None:
        path = fit_to_kernel(path)
        environ['FASTRTPS_DEFAULT_PROFILES_FILE'] = path
    return path
