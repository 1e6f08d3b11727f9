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

"""The packaged Fast DDS profile: used by default, never over a user's choice, kernel-safe."""

from pathlib import Path
import xml.etree.ElementTree as ET

from py_vision import dds

NS = '{http://www.eprosima.com/XMLSchemas/fastRTPS_Profiles}'


def buffer_sizes(path):
    root = ET.parse(path).getroot()
    return {tag: int(root.find('.//%s%s' % (NS, tag)).text)
            for tag in ('sendBufferSize', 'receiveBufferSize')}


def without_buffer_sizes(path):
    root = ET.parse(path).getroot()
    for tag in ('sendBufferSize', 'receiveBufferSize'):
        root.find('.//%s%s' % (NS, tag)).text = ''
    return ET.tostring(root)


def test_installed_profile_gives_shared_memory_room_for_frames():
    path = dds.packaged_profile()
    assert path is not None and 'install' in path
    root = ET.parse(path).getroot()
    segment = int(root.find('.//%ssegment_size' % NS).text)
    assert segment >= 2 * 1920 * 1080 * 3, 'room for two 1080p bgr8 frames in flight'
    assert segment <= 32 << 20, 'every node allocates it whole: boards have 1 GB of RAM'
    transports = [t.text for t in root.iter(NS + 'transport_id')]
    assert 'py_vision_shm' in transports and 'py_vision_udp' in transports


def test_used_by_default_and_capped_to_the_kernel_limits(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    env = {}
    used = dds.use_packaged_profile(env)
    assert env['FASTRTPS_DEFAULT_PROFILES_FILE'] == used
    limits = {'sendBufferSize': '/proc/sys/net/core/wmem_max',
              'receiveBufferSize': '/proc/sys/net/core/rmem_max'}
    for tag, size in buffer_sizes(used).items():
        assert size <= int(Path(limits[tag]).read_text())


def test_buffers_above_the_limit_are_capped_in_a_copy(tmp_path):
    packaged = dds.packaged_profile()
    fitted = dds.fit_to_kernel(packaged, {'sendBufferSize': 212992,
                                          'receiveBufferSize': 212992})
    assert fitted != packaged
    assert buffer_sizes(fitted) == {'sendBufferSize': 212992, 'receiveBufferSize': 212992}
    # Everything else is the packaged profile.
    assert without_buffer_sizes(fitted) == without_buffer_sizes(packaged)
    big = {'sendBufferSize': 1 << 30, 'receiveBufferSize': 1 << 30}
    assert dds.fit_to_kernel(packaged, big) == packaged


def test_user_settings_and_other_rmws_are_left_alone(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    for env in ({'FASTRTPS_DEFAULT_PROFILES_FILE': '/etc/mine.xml'},
                {'FASTDDS_DEFAULT_PROFILES_FILE': '/etc/mine.xml'},
                {'RMW_IMPLEMENTATION': 'rmw_cyclonedds_cpp'}):
        before = dict(env)
        assert dds.use_packaged_profile(env) is None
        assert env == before
    env = {'RMW_IMPLEMENTATION': 'rmw_fastrtps_cpp'}
    assert dds.use_packaged_profile(env) is not None
    # Fast DDS reads DEFAULT_FASTRTPS_PROFILES.xml from the working directory by itself.
    (tmp_path / 'DEFAULT_FASTRTPS_PROFILES.xml').write_text('<profiles/>')
    env = {}
    assert dds.use_packaged_profile(env) is None and env == {}
