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
The board image's Fast DDS patches, applied to Fast DDS 2.6.0's own files and run.

fixtures/fast-dds-2.6.0 holds the files of Fast DDS v2.6.0 that the bbappend's patches change
and what they include, unchanged (the same bytes as in meta-ros' fastrtps 2.6.0-3 sources:
ORIGIN.txt). The patches are applied to a copy in the bbappend's SRC_URI order with GNU patch
and no fuzz, as the image's build does. fast_dds_recovery.cpp is then compiled against the
patched files and Debian's Boost headers, and run: a reader process takes a message and exits
without finishing it, as a crashed participant does, and the writer runs Fast DDS' recovery of
the buffer the dead reader held. With df904f30 alone the recovery locks the port's
empty_cv_mutex while holding it (the program sees the same thread lock it again, three passes
in a row, each giving up after Fast DDS' 1 s): the recovery never ends. With both patches it
ends and the buffer can be allocated again.

Without g++, Debian's libboost-dev or patch these tests are skipped with the reason, and fail
in CI (scripts/test.sh installs them).
"""

import hashlib
import os
from pathlib import Path
import re
import shutil
import subprocess

import pytest

HERE = Path(__file__).resolve().parent
SOURCES = HERE / 'fixtures' / 'fast-dds-2.6.0'
HARNESS = HERE / 'fast_dds_recovery.cpp'
BBAPPEND = HERE.parent / 'meta-user' / 'recipes-ros' / 'fastrtps' / 'fastrtps_2.6.0-3.bbappend'
PATCH_DIR = BBAPPEND.parent / 'files'
FIRST = '0001-Improve-SHM-resilience-to-crashing-participants-3765.patch'
SECOND = '0002-Fix-SharedMem-self-deadlock-in-blocked-processing-re.patch'
# The harness: exit 0 recovered, 3 a thread locked a mutex it held (the self-deadlock).
RECOVERED, SELF_DEADLOCK = 0, 3
# Compiling takes 5 to 10 s here; the run, under 4 s either way.
COMPILE_TIMEOUT, RUN_TIMEOUT = 600, 120


def _unavailable(why: str) -> None:
    if os.environ.get('CI') == 'true':
        pytest.fail(why + ', and CI requires it (scripts/test.sh installs it)')
    pytest.skip(why)


def bbappend_patches() -> list:
    """Return the patch files the bbappend adds to SRC_URI, in order."""
    text = BBAPPEND.read_text()
    entries = []
    for value in re.findall(r'^SRC_URI\s*\+=\s*"([^"]*)"', text, re.M):
        entries += value.split()
    return [entry[len('file://'):].split(';')[0] for entry in entries
            if entry.startswith('file://') and entry.split(';')[0].endswith('.patch')]


def blob_id(data: bytes) -> str:
    """Return git's id of a file with these bytes (git hash-object)."""
    return hashlib.sha1(b'blob %d\0' % len(data) + data).hexdigest()


def origin_blobs() -> dict:
    """Return {path: blob id} as fixtures/fast-dds-2.6.0/ORIGIN.txt lists them."""
    lines = (SOURCES / 'ORIGIN.txt').read_text().splitlines()
    return {m.group(2): m.group(1) for m in map(re.compile(r'([0-9a-f]{40}) (\S+)$').match, lines)
            if m}


def patch(tree: Path, name: str, *options) -> subprocess.CompletedProcess:
    """Run GNU patch with one of the bbappend's patches in tree, with no fuzz."""
    if shutil.which('patch') is None:
        _unavailable('GNU patch is missing (Debian: patch)')
    return subprocess.run(
        ['patch', '-p1', '--fuzz=0', '--forward', '--no-backup-if-mismatch', *options, '-i',
         str(PATCH_DIR / name)], cwd=tree, capture_output=True, text=True, timeout=60)


def apply_patches(tree: Path, names) -> list:
    """Apply the patches to a copy of Fast DDS' files in tree; return patch's outputs."""
    shutil.copytree(SOURCES, tree)
    outputs = []
    for name in names:
        result = patch(tree, name)
        after = ' after ' + ', '.join(names[:len(outputs)]) if outputs else ''
        assert result.returncode == 0, '%s does not apply to Fast DDS 2.6.0%s:\n%s%s' % (
            name, after, result.stdout, result.stderr)
        outputs.append(result.stdout)
    return outputs


def compile_harness(tree: Path) -> Path:
    """Compile fast_dds_recovery.cpp against the Fast DDS files in tree; return the program."""
    compiler = shutil.which('g++')
    if compiler is None:
        _unavailable('no C++ compiler (Debian: g++)')
    program = tree / 'fast_dds_recovery'
    result = subprocess.run(
        [compiler, '-std=c++11', '-O1', '-o', str(program), str(HARNESS),
         '-I', str(tree / 'src' / 'cpp'), '-I', str(tree / 'thirdparty' / 'boost' / 'include'),
         '-pthread', '-lrt', '-Wl,--wrap=pthread_mutex_timedlock'],
        capture_output=True, text=True, timeout=COMPILE_TIMEOUT)
    if result.returncode and re.search(r'boost/\S+: No such file or directory', result.stderr):
        _unavailable("Boost's headers are missing (Debian: libboost-dev)")
    assert result.returncode == 0, 'the harness does not compile:\n' + result.stderr[-6000:]
    return program


def run_harness(program: Path, tag: str) -> subprocess.CompletedProcess:
    """Run the harness on a shared-memory domain of its own, and remove the domain's files."""
    # At most 16 characters: Fast DDS' limit for a domain name.
    domain = 'pyv%d%s' % (os.getpid() % 100000, tag)
    try:
        return subprocess.run([str(program), domain], capture_output=True, text=True,
                              timeout=RUN_TIMEOUT, start_new_session=True)
    finally:
        for leftover in Path('/dev/shm').glob('*%s_*' % domain):
            leftover.unlink(missing_ok=True)


def describe(result: subprocess.CompletedProcess) -> str:
    return 'exit status %d\n--- output:\n%s--- stderr:\n%s' % (
        result.returncode, result.stdout, result.stderr)


def test_the_fixture_is_fast_dds_2_6_0_unchanged():
    blobs = origin_blobs()
    found = sorted(str(path.relative_to(SOURCES)) for path in SOURCES.rglob('*')
                   if path.is_file() and path.name != 'ORIGIN.txt')
    assert found == sorted(blobs), 'ORIGIN.txt and the files differ'
    changed = [path for path, blob in blobs.items()
               if blob_id((SOURCES / path).read_bytes()) != blob]
    assert not changed, 'not the bytes of Fast DDS v2.6.0: %s' % changed


def test_the_bbappend_applies_df904f30_then_f6f665a4():
    assert bbappend_patches() == [FIRST, SECOND]
    for name, commit in ((FIRST, 'df904f302a443c64ea4b542e8fd486f58be50a47'),
                         (SECOND, 'f6f665a4ad060357df693e8f728a9e4e4ea44cb4')):
        text = (PATCH_DIR / name).read_text()
        assert text.startswith('From %s ' % commit), name
        assert re.search(r'^Upstream-Status: (Backport|Submitted) \[https://github.com/eProsima/'
                         r'Fast-DDS/\S+', text, re.M), name
    # The second is a backport (a part of its commit): its header says so, and which part.
    assert 'Backported to Fast DDS 2.6.0' in (PATCH_DIR / SECOND).read_text()


def test_the_patches_apply_in_order_without_fuzz(tmp_path):
    outputs = apply_patches(tmp_path / 'fast-dds', bbappend_patches())
    for output in outputs:
        assert 'fuzz' not in output and 'FAILED' not in output, output
    patched = (tmp_path / 'fast-dds' / 'src/cpp/rtps/transport/shared_mem/'
               'SharedMemGlobal.hpp').read_text()
    recovery = re.search(r'bool get_and_remove_blocked_processing\(.*?\n        }\n', patched,
                         re.S).group(0)
    assert 'listener_processing_stop(' not in recovery, recovery


def test_the_second_patch_needs_the_first(tmp_path):
    shutil.copytree(SOURCES, tmp_path / 'fast-dds')
    result = patch(tmp_path / 'fast-dds', SECOND, '--dry-run')
    assert result.returncode != 0 and 'FAILED' in result.stdout, result.stdout


def test_with_both_patches_the_recovery_frees_the_dead_readers_buffer(tmp_path):
    apply_patches(tmp_path / 'fast-dds', bbappend_patches())
    result = run_harness(compile_harness(tmp_path / 'fast-dds'), 'b')
    assert result.returncode == RECOVERED, describe(result)
    assert 'its only buffer is held by the dead reader' in result.stdout, describe(result)
    assert 'the buffer is free again: RECOVERED' in result.stdout, describe(result)
    assert 'self-lock' not in result.stdout, describe(result)


def test_with_df904f30_alone_the_recovery_locks_its_mutex_twice(tmp_path):
    # The image before f6f665a4: what the test above fails on (the harness sees it).
    apply_patches(tmp_path / 'fast-dds', [FIRST])
    result = run_harness(compile_harness(tmp_path / 'fast-dds'), 'a')
    assert result.returncode == SELF_DEADLOCK, describe(result)
    assert 'self-lock 3 (recover_blocked_processing())' in result.stdout, describe(result)
    assert 'RECOVERED' not in result.stdout, describe(result)


def test_fast_dds_2_6_0_as_released_recovers(tmp_path):
    # The second lock came with df904f30: without it, listener_processing_stop took no lock.
    shutil.copytree(SOURCES, tmp_path / 'fast-dds')
    result = run_harness(compile_harness(tmp_path / 'fast-dds'), 'r')
    assert result.returncode == RECOVERED, describe(result)
    assert 'self-lock' not in result.stdout, describe(result)
