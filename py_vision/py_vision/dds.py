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
"""

import os

from ament_index_python.packages import get_package_share_directory, PackageNotFoundError

PROFILE_NAME = 'fastdds_image_profile.xml'
_USER_SETTINGS = ('FASTRTPS_DEFAULT_PROFILES_FILE', 'FASTDDS_DEFAULT_PROFILES_FILE')
_FAST_DDS_RMWS = ('', 'rmw_fastrtps_cpp', 'rmw_fastrtps_dynamic_cpp')


def packaged_profile():
    """Return the installed profile's path, or None when the package is not installed."""
    try:
        share = get_package_share_directory('py_vision')
    except PackageNotFoundError:
        return None
    path = os.path.join(share, 'config', PROFILE_NAME)
    return path if os.path.isfile(path) else None


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
        environ['FASTRTPS_DEFAULT_PROFILES_FILE'] = path
    return path
