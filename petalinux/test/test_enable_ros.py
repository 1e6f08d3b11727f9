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
petalinux/enable_ros.py on PetaLinux 2023.2 project skeletons of the three boards.

The skeletons (fixtures/<board>/) hold what petalinux-create and the Avnet board scripts leave:
the project settings, a long Kconfig rootfs_config with its menu banners, 'is not set' lines
and user packages block, a user-rootfsconfig with the PetaLinux note and the board's own
packages, and the meta-user layer's conf/layer.conf as PetaLinux 2023.2 writes it. Each test
derives a starting state from them, runs the tool as a user would, and checks the result with
petalinux_model (what PetaLinux, Kconfig and bitbake read), line by line.
"""

import difflib
import importlib.util
import os
from pathlib import Path
import re
import shutil
import subprocess
import sys

import petalinux_model as model
import pytest

HERE = Path(__file__).resolve().parent
TOOL = HERE.parent / 'enable_ros.py'
FIXTURES = HERE / 'fixtures'
USER = Path('project-spec/meta-user/conf/user-rootfsconfig')
ROOTFS = Path('project-spec/configs/rootfs_config')
CONFIG = Path('project-spec/configs/config')
META_USER = Path('project-spec/meta-user')
LAYER_CONF = META_USER / 'conf' / 'layer.conf'
LAYER_SOURCE = HERE.parent / 'meta-user'

# The tutorial's eight packages, then what py_vision runs on whatever they bring (OpenCV's and
# numpy's Python modules, PyYAML), xauth for ssh -X windows, vision-msgs for the faces step's
# detections and the TensorFlow Lite runtime of the model steps: every board's fragments hold
# these today, in this order.
TUTORIAL = ['packagegroup-petalinux-ros', 'packagegroup-petalinux-ros-dev', 'cv-bridge',
            'cv-bridge-dev', 'v4l2-camera', 'v4l2-camera-dev', 'turtlesim', 'turtlesim-dev']
RUNTIME = ['python3-opencv', 'python3-numpy', 'python3-pyyaml', 'xauth', 'vision-msgs',
           'python3-tflite-runtime']
# The files the tool places in the project's meta-user layer, in the order it goes through
# them: the runtime's recipe with the licence text of its fft2d, and the bbappend of meta-ros'
# Fast DDS recipe with the two upstream patches it applies.
RECIPE = 'recipes-python/python3-tflite-runtime/python3-tflite-runtime_2.14.0.bb'
FFT2D_LICENCE = 'recipes-python/python3-tflite-runtime/files/readme2d.txt'
BBAPPEND = 'recipes-ros/fastrtps/fastrtps_2.6.0-3.bbappend'
PATCH = ('recipes-ros/fastrtps/files/'
         '0001-Improve-SHM-resilience-to-crashing-participants-3765.patch')
PATCH2 = ('recipes-ros/fastrtps/files/'
          '0002-Fix-SharedMem-self-deadlock-in-blocked-processing-re.patch')
LAYER_FILES = [RECIPE, FFT2D_LICENCE, BBAPPEND, PATCH, PATCH2]
# The Fast DDS recipe of PetaLinux 2023.2's meta-ros (branch rel-v2023.2, meta-ros2-humble).
META_ROS_FASTRTPS = 'fastrtps_2.6.0-3.bb'
PACKAGES = TUTORIAL + RUNTIME
BOARDS = {'zub1cg': 'zub1cg-sbc-2023-2', 'u96v2': 'u96v2-sbc-2023-2',
          'uz7ev': 'uz7ev-evcc-2023-2'}


def load_tool():
    spec = importlib.util.spec_from_file_location('enable_ros', TOOL)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


enable_ros = load_tool()


def run_tool(*args, umask=None):
    """Run the tool as a user does; return the CompletedProcess (text output)."""
    result = subprocess.run([sys.executable, str(TOOL)] + [str(a) for a in args],
                            capture_output=True, text=True, timeout=30,
                            preexec_fn=None if umask is None else lambda: os.umask(umask))
    assert 'Traceback' not in result.stderr, result.stderr
    return result


# ---------------------------------------------------------------------------------------------
# Starting states

def block_entries(text, entries):
    """Return rootfs_config text with entries {name: line} merged, sorted, into its block."""
    lines = text.split('\n')
    start = lines.index('# user packages ') + 2
    end = start
    while lines[end].startswith(('CONFIG_', '# CONFIG_')):
        end += 1
    block = lines[start:end] + list(entries.values())
    block.sort(key=lambda line: re.search(r'CONFIG_([^= ]+)', line).group(1))
    return '\n'.join(lines[:start] + block + lines[end:])


def without_block(text):
    """Return rootfs_config text without its user packages menu (banner and entries)."""
    return re.sub(r'\n#\n# user packages \n#\n(?:(?:# )?CONFIG_[^\n]*\n)*', '', text)


def make_project(tmp_path, board, state):
    """Copy a board's skeleton and put it in a starting state; return the project dir."""
    project = tmp_path / board
    shutil.copytree(FIXTURES / board, project)
    user = (project / USER).read_text()
    rootfs = (project / ROOTFS).read_text()
    if state == 'declared_not_set':
        # The tutorial's packages declared, and petalinux-config has run: the packagegroups are
        # 'is not set', the bridge is on, the rest was never written.
        user += ''.join('CONFIG_%s\n' % name for name in TUTORIAL)
        rootfs = block_entries(rootfs, {
            'packagegroup-petalinux-ros': '# CONFIG_packagegroup-petalinux-ros is not set',
            'packagegroup-petalinux-ros-dev':
                '# CONFIG_packagegroup-petalinux-ros-dev is not set',
            'cv-bridge': 'CONFIG_cv-bridge=y', 'cv-bridge-dev': 'CONFIG_cv-bridge-dev=y'})
    elif state == 'commented':
        user += ''.join(('#CONFIG_%s\n', '# CONFIG_%s\n')[i % 2] % name
                        for i, name in enumerate(PACKAGES))
    elif state == 'no_final_newline':
        user = user.rstrip('\n')
        rootfs = without_block(rootfs).rstrip('\n')
    elif state == 'no_block':
        rootfs = without_block(rootfs)
    elif state == 'enabled':
        user += ''.join('CONFIG_%s\n' % name for name in PACKAGES)
        rootfs = block_entries(rootfs, {name: 'CONFIG_%s=y' % name for name in PACKAGES})
        shutil.copytree(LAYER_SOURCE, project / META_USER, dirs_exist_ok=True)
    elif state == 'apps_only_layer':
        # A meta-user layer.conf edited to read its recipes-apps alone.
        (project / LAYER_CONF).write_text(
            'BBPATH .= ":${LAYERDIR}"\n'
            'BBFILES += "${LAYERDIR}/recipes-apps/*/*.bb \\\n'
            '\t${LAYERDIR}/recipes-apps/*/*.bbappend"\n'
            'BBFILE_COLLECTIONS += "meta-user"\n'
            'BBFILE_PATTERN_meta-user = "^${LAYERDIR}/"\n'
            'BBFILE_PRIORITY_meta-user = "7"\n'
            'LAYERSERIES_COMPAT_meta-user = "langdale"')
    elif state == 'tutorial':
        # Everything the tutorial says, done by hand before py_vision's own packages existed.
        user += ''.join('CONFIG_%s\n' % name for name in TUTORIAL)
        rootfs = block_entries(rootfs, {name: 'CONFIG_%s=y' % name for name in TUTORIAL})
    elif state == 'other_menu':
        # Packages that a PetaLinux menu of its own lists, switched off there.
        rootfs = re.sub(r'(\n(# )?CONFIG_python3-pip[^\n]*\n)',
                        r'\1# CONFIG_python3-numpy is not set\nCONFIG_xauth=n\n', rootfs, count=1)
    elif state == 'crlf':
        user, rootfs = user.replace('\n', '\r\n'), rootfs.replace('\n', '\r\n')
        layer_conf = (project / LAYER_CONF).read_bytes()
        (project / LAYER_CONF).write_bytes(layer_conf.replace(b'\n', b'\r\n'))
    elif state == 'messy':
        user += ('# CONFIG_cv-bridge is not set\n'  # pasted from rootfs_config: not cv-bridge
                 'CONFIG_cv-bridge\n'
                 '#CONFIG_turtlesim\n'
                 'CONFIG_cv-bridge\n'
                 '  CONFIG_v4l2-camera  \n')
        rootfs = block_entries(rootfs, {
            'cv-bridge': 'CONFIG_cv-bridge=y',
            'turtlesim': 'CONFIG_turtlesim=m',
            'v4l2-camera': 'CONFIG_v4l2-camera=y ',
            'turtlesim-dev': 'CONFIG_turtlesim-dev=y'})
        rootfs += ('\n#\n# Appended by hand\n#\nCONFIG_cv-bridge=y\n'
                   '# CONFIG_turtlesim-dev is not set\nCONFIG_v4l2-camera-dev=n\n')
    else:
        assert state == 'fresh'
    (project / USER).write_bytes(user.encode())
    (project / ROOTFS).write_bytes(rootfs.encode())
    return project


STATES = ['fresh', 'declared_not_set', 'commented', 'no_final_newline', 'no_block', 'enabled',
          'tutorial', 'other_menu', 'crlf', 'messy', 'apps_only_layer']


# ---------------------------------------------------------------------------------------------
# What a correct result looks like

def assert_enabled(project):
    """Assert PetaLinux declares and Kconfig enables every package, bitbake reads the layer."""
    user = (project / USER).read_bytes()
    rootfs = (project / ROOTFS).read_bytes()
    declared = model.declarations(user)
    values = model.assignments(rootfs)
    installed = model.image_packages(rootfs)
    for name in PACKAGES:
        assert declared.count(name) == 1, (name, declared)
        assert values.get(name) == ['y'], (name, values.get(name))
        assert installed.count(name) == 1, name
    lines = model.kconfig_lines(user)
    assert all('CONFIG_%s' % name in lines for name in PACKAGES)
    assert_layer_in_place(project)


def assert_layer_in_place(project):
    """Assert the layer files are there as petalinux/meta-user has them, and bitbake reads them."""
    for relative in LAYER_FILES:
        assert (project / META_USER / relative).read_bytes() == (
            LAYER_SOURCE / relative).read_bytes(), relative
    read = model.bbfiles((project / LAYER_CONF).read_bytes(), project / META_USER)
    assert str(project / META_USER / RECIPE) in read, read
    assert str(project / META_USER / BBAPPEND) in read, read
    appends = [Path(path).name for path in read if path.endswith('.bbappend')]
    assert [name for name in appends if model.appends_to(name, META_ROS_FASTRTPS)] == [
        Path(BBAPPEND).name]


def raw_lines(data):
    return data.decode('utf-8', 'surrogateescape').splitlines(keepends=True)


def package_line(line):
    """Return whether a line (with or without its end) is about one of our packages."""
    text = line.rstrip('\r\n')
    match = re.search(r'CONFIG_([^= ]+)', text)
    return bool(match) and match.group(1) in PACKAGES


def assert_only_package_lines_changed(before, after):
    """Assert the only differences are lines of our packages and a newline given to a last line."""
    old, new = raw_lines(before), raw_lines(after)
    matcher = difflib.SequenceMatcher(a=old, b=new, autojunk=False)
    for op, a0, a1, b0, b1 in matcher.get_opcodes():
        if op == 'equal':
            continue
        removed, added = old[a0:a1], new[b0:b1]
        if removed and not removed[-1].endswith('\n') and a1 == len(old):
            # The old last line, which had no newline, may only have gained one.
            assert added and added[0] == removed[-1] + added[0][len(removed[-1]):], added
            assert added[0][len(removed[-1]):] in ('\n', '\r\n')
            removed, added = removed[:-1], added[1:]
        assert all(package_line(line) for line in removed), removed
        for line in added:
            assert re.fullmatch(r'CONFIG_([^=\s]+)(=y)?\r?\n', line), line
            assert package_line(line), line


def neighbours(lines, index):
    """Return the nearest lines above and below lines[index] that are not lines of our packages."""
    above = next(line for line in reversed(lines[:index]) if not package_line(line))
    below = next((line for line in lines[index + 1:] if not package_line(line)), None)
    return above, below


def assert_in_place(before, old, after, new):
    """Assert line new of after stands where line old stood in before."""
    assert after.count(new) == 1
    assert neighbours(after, after.index(new)) == neighbours(before, before.index(old))


# ---------------------------------------------------------------------------------------------
# Every board, every starting state

def project_files(project):
    """Return {path relative to the project: bytes} of every file of the project."""
    return {path.relative_to(project): path.read_bytes()
            for path in sorted(project.rglob('*')) if path.is_file()}


@pytest.mark.parametrize('state', STATES)
@pytest.mark.parametrize('board', sorted(BOARDS))
def test_enables_every_state_and_is_idempotent(tmp_path, board, state):
    project = make_project(tmp_path, board, state)
    before = project_files(project)

    check = run_tool(project, '--check')
    assert check.returncode == (0 if state == 'enabled' else 1), check.stdout
    assert project_files(project) == before

    first = run_tool(project)
    assert first.returncode == 0, first.stderr
    assert 'board: %s' % board in first.stdout
    assert 'petalinux-config -c rootfs --silentconfig' in first.stdout
    assert_enabled(project)
    after = project_files(project)
    for path in (USER, ROOTFS):
        assert_only_package_lines_changed(before[path], after[path])
    # The layer files are added, nothing else of the project is touched but for layer.conf,
    # which only a layer.conf that does not pick up the recipes gets a BBFILES line in.
    assert set(after) == set(before) | {META_USER / relative for relative in LAYER_FILES}
    assert {path: data for path, data in after.items()
            if path in before and path not in (USER, ROOTFS, LAYER_CONF)} == {
        path: data for path, data in before.items() if path not in (USER, ROOTFS, LAYER_CONF)}
    if state == 'apps_only_layer':
        assert after[LAYER_CONF] == before[LAYER_CONF] + (
            b'\nBBFILES += "${LAYERDIR}/recipes-*/*/*.bb ${LAYERDIR}/recipes-*/*/*.bbappend"\n')
        assert 'layer.conf: BBFILES line appended' in first.stdout
    else:
        assert after[LAYER_CONF] == before[LAYER_CONF]
        assert 'layer.conf: BBFILES already picks up the recipes' in first.stdout
    if state == 'enabled':
        assert after == before
        assert 'nothing to change' in first.stdout
    else:
        assert 'meta-user: placed %d file(s), replaced 0, already 0' % len(LAYER_FILES) in (
            first.stdout)

    second = run_tool(project)
    assert second.returncode == 0
    assert 'nothing to change' in second.stdout
    assert project_files(project) == after
    assert run_tool(project, '--check').returncode == 0


def test_fresh_project_adds_in_sorted_block_and_appends_declarations(tmp_path):
    project = make_project(tmp_path, 'zub1cg', 'fresh')
    before_user = (project / USER).read_text()
    assert run_tool(project).returncode == 0
    user = (project / USER).read_text()
    assert user == before_user + ''.join('CONFIG_%s\n' % name for name in PACKAGES)
    lines = (project / ROOTFS).read_text().split('\n')
    start = lines.index('# user packages ') + 2
    end = lines.index('', start)
    names = [re.search(r'CONFIG_([^= ]+)', line).group(1) for line in lines[start:end]]
    assert names == sorted(names)
    assert set(PACKAGES) <= set(names)
    assert 'gpio-demo' in names and 'blinky' in names  # the board's own packages stay
    assert lines[end + 2] == '# PetaLinux RootFS Settings'


def test_is_not_set_lines_are_switched_in_place(tmp_path):
    project = make_project(tmp_path, 'u96v2', 'declared_not_set')
    before = (project / ROOTFS).read_text().split('\n')
    user_before = (project / USER).read_bytes()
    result = run_tool(project)
    after = (project / ROOTFS).read_text().split('\n')
    for name in ('packagegroup-petalinux-ros', 'packagegroup-petalinux-ros-dev'):
        assert_in_place(before, '# CONFIG_%s is not set' % name, after, 'CONFIG_%s=y' % name)
    # The tutorial's declarations stay as they are; py_vision's own packages are appended.
    assert (project / USER).read_bytes() == user_before + b''.join(
        b'CONFIG_%s\n' % name.encode() for name in RUNTIME)
    assert 'user-rootfsconfig: declared 6, already 8' in result.stdout
    assert 'rootfs_config: enabled 12, already 2' in result.stdout


def test_a_tutorial_project_gets_exactly_what_py_vision_runs_on(tmp_path):
    # A project that followed the tutorial has the eight ROS packages and lacks OpenCV's and
    # numpy's Python modules, PyYAML, xauth, vision-msgs and the TensorFlow Lite runtime as
    # packages of its own, and py_vision's recipes.
    project = make_project(tmp_path, 'zub1cg', 'tutorial')
    check = run_tool(project, '--check')
    assert check.returncode == 1
    problems = [line.strip() for line in check.stdout.split('problem(s):')[1].splitlines()
                if line.startswith('  ')]
    assert problems == (['user-rootfsconfig: %s: not declared' % name for name in RUNTIME]
                        + ['rootfs_config: %s: not assigned' % name for name in RUNTIME]
                        + ['meta-user: %s: missing' % relative for relative in LAYER_FILES])
    before = (project / ROOTFS).read_text().split('\n')
    result = run_tool(project)
    assert result.returncode == 0, result.stderr
    assert 'user-rootfsconfig: declared 6, already 8' in result.stdout
    assert 'rootfs_config: enabled 6, already 8' in result.stdout
    after = (project / ROOTFS).read_text().split('\n')
    start = after.index('# user packages ') + 2
    block = after[start:after.index('', start)]
    names = [re.search(r'CONFIG_([^= ]+)', line).group(1) for line in block]
    assert names == sorted(names)  # the new ones in sorted place among the block's own
    assert {'CONFIG_%s=y' % name for name in PACKAGES} <= set(block)
    assert len(after) == len(before) + len(RUNTIME)
    installed = model.image_packages((project / ROOTFS).read_bytes())
    assert all(installed.count(name) == 1 for name in RUNTIME)


def test_packages_in_a_petalinux_menu_are_switched_on_there(tmp_path):
    project = make_project(tmp_path, 'u96v2', 'other_menu')
    before = (project / ROOTFS).read_text().split('\n')
    assert run_tool(project).returncode == 0
    after = (project / ROOTFS).read_text().split('\n')
    assert_in_place(before, '# CONFIG_python3-numpy is not set', after,
                    'CONFIG_python3-numpy=y')
    assert_in_place(before, 'CONFIG_xauth=n', after, 'CONFIG_xauth=y')
    assert model.assignments((project / ROOTFS).read_bytes())['xauth'] == ['y']
    assert_enabled(project)


def test_commented_declarations_are_uncommented_in_place(tmp_path):
    project = make_project(tmp_path, 'uz7ev', 'commented')
    before = (project / USER).read_text().split('\n')
    assert run_tool(project).returncode == 0
    after = (project / USER).read_text().split('\n')
    assert len(after) == len(before)
    for name in PACKAGES:
        commented = [line for line in before if line.lstrip('# ') == 'CONFIG_' + name]
        assert after.index('CONFIG_' + name) == before.index(commented[0])


def test_missing_final_newline_is_never_glued(tmp_path):
    project = make_project(tmp_path, 'zub1cg', 'no_final_newline')
    user_before = (project / USER).read_bytes()
    rootfs_before = (project / ROOTFS).read_bytes()
    assert not user_before.endswith(b'\n') and not rootfs_before.endswith(b'\n')
    assert run_tool(project).returncode == 0
    assert (project / USER).read_bytes() == user_before + b'\n' + b''.join(
        b'CONFIG_%s\n' % name.encode() for name in PACKAGES)
    assert (project / ROOTFS).read_bytes() == rootfs_before + b'\n' + b''.join(
        b'CONFIG_%s=y\n' % name.encode() for name in PACKAGES)
    assert b'CONFIG_ADD_USERS_TO_SUDOERS="petalinux"\n' in (project / ROOTFS).read_bytes()


def test_crlf_files_stay_crlf(tmp_path):
    project = make_project(tmp_path, 'u96v2', 'crlf')
    assert run_tool(project).returncode == 0
    for path in (USER, ROOTFS):
        data = (project / path).read_bytes()
        assert data.count(b'\n') == data.count(b'\r\n') > 0


def test_duplicates_and_non_y_values_end_as_one_y(tmp_path):
    project = make_project(tmp_path, 'zub1cg', 'messy')
    before = (project / ROOTFS).read_text().split('\n')
    result = run_tool(project)
    assert result.returncode == 0
    after = (project / ROOTFS).read_text().split('\n')
    # A non-y value is rewritten where it stands; later repeats are removed.
    assert_in_place(before, 'CONFIG_turtlesim=m', after, 'CONFIG_turtlesim=y')
    assert_in_place(before, 'CONFIG_v4l2-camera=y ', after, 'CONFIG_v4l2-camera=y')
    assert 'CONFIG_v4l2-camera-dev=n' not in after
    assert after.count('CONFIG_cv-bridge=y') == 1
    assert '# CONFIG_turtlesim-dev is not set' not in after
    user = (project / USER).read_text().split('\n')
    assert user.count('CONFIG_cv-bridge') == 1
    assert 'CONFIG_turtlesim' in user and '#CONFIG_turtlesim' not in user
    assert 'CONFIG_v4l2-camera' in user
    # The pasted 'is not set' comment is a broken declaration for PetaLinux: left alone, and
    # the user is told.
    assert '# CONFIG_cv-bridge is not set' in user
    assert "PetaLinux still reads it as declaring 'cv-bridge is not set'" in result.stderr


def test_other_bytes_survive_even_when_not_utf8(tmp_path):
    project = make_project(tmp_path, 'uz7ev', 'fresh')
    odd = b'\xef\xbb\xbf#Paquets ajout\xe9s \xa0\n'
    (project / USER).write_bytes(odd + (project / USER).read_bytes())
    before = (project / USER).read_bytes()
    assert run_tool(project).returncode == 0
    after = (project / USER).read_bytes()
    assert after.startswith(before)
    assert model.declarations(after)[-len(PACKAGES):] == PACKAGES


# ---------------------------------------------------------------------------------------------
# The modes and the errors

def test_dry_run_prints_the_diff_and_writes_nothing(tmp_path):
    project = make_project(tmp_path, 'zub1cg', 'declared_not_set')
    before = {path: (project / path).read_bytes() for path in (USER, ROOTFS)}
    stamps = {path: (project / path).stat().st_mtime_ns for path in before}
    result = run_tool(project, '--dry-run')
    assert result.returncode == 0
    assert '-# CONFIG_packagegroup-petalinux-ros is not set' in result.stdout
    assert '+CONFIG_packagegroup-petalinux-ros=y' in result.stdout
    assert '+CONFIG_v4l2-camera=y' in result.stdout
    assert 'dry run: nothing written' in result.stdout
    assert {path: (project / path).read_bytes() for path in before} == before
    assert {path: (project / path).stat().st_mtime_ns for path in before} == stamps
    assert sorted(os.listdir(project / ROOTFS.parent)) == ['config', 'rootfs_config']


def test_check_lists_what_is_missing(tmp_path):
    project = make_project(tmp_path, 'uz7ev', 'declared_not_set')
    result = run_tool(project, '--check')
    assert result.returncode == 1
    assert 'rootfs_config: packagegroup-petalinux-ros: line' in result.stdout
    assert 'rootfs_config: turtlesim-dev: not assigned' in result.stdout
    problems = result.stdout.split('problem(s):')[1]
    assert [line.strip() for line in problems.splitlines() if 'user-rootfsconfig' in line] == [
        'user-rootfsconfig: %s: not declared' % name for name in RUNTIME]
    assert 'rootfs_config: cv-bridge:' not in result.stdout


@pytest.mark.parametrize('board', sorted(BOARDS))
def test_board_is_read_from_the_project_settings(tmp_path, board):
    project = make_project(tmp_path, board, 'fresh')
    assert enable_ros.detect_board(str(project)) == (
        board, 'CONFIG_SUBSYSTEM_HOSTNAME="%s"' % BOARDS[board])


@pytest.mark.parametrize('hostname, machine, board', [
    ('my-robot', 'zub1cg-sbc-dualcam', 'zub1cg'),
    ('ultra96v2-ros', 'zynqmp-generic', 'u96v2'),
    ('UZ7EV_EVCC_2023_2', 'zynqmp-generic', 'uz7ev'),
])
def test_board_detection_variants(tmp_path, hostname, machine, board):
    project = make_project(tmp_path, 'zub1cg', 'fresh')
    config = (project / CONFIG).read_text()
    config = re.sub(r'(CONFIG_SUBSYSTEM_(HOSTNAME|PRODUCT))="[^"]*"', r'\1="%s"' % hostname,
                    config)
    config = re.sub(r'CONFIG_YOCTO_MACHINE_NAME="[^"]*"',
                    'CONFIG_YOCTO_MACHINE_NAME="%s"' % machine, config)
    (project / CONFIG).write_text(config)
    assert enable_ros.detect_board(str(project))[0] == board


def test_unknown_board_is_refused_until_given(tmp_path):
    project = make_project(tmp_path, 'u96v2', 'fresh')
    config = (project / CONFIG).read_text()
    config = re.sub(r'u96v2-sbc(-2023-2|-2023\.2)?', 'custom-board', config)
    (project / CONFIG).write_text(config)
    before = (project / ROOTFS).read_bytes()
    refused = run_tool(project)
    assert refused.returncode == 2
    assert 'cannot tell the board' in refused.stderr
    assert '--board zub1cg|u96v2|uz7ev' in refused.stderr
    assert (project / ROOTFS).read_bytes() == before
    given = run_tool(project, '--board', 'u96v2')
    assert given.returncode == 0, given.stderr
    assert 'given with --board' in given.stdout
    assert_enabled(project)


def test_board_flag_works_without_project_settings(tmp_path):
    project = make_project(tmp_path, 'uz7ev', 'fresh')
    (project / CONFIG).unlink()
    assert run_tool(project).returncode == 2
    assert run_tool(project, '--board', 'uz7ev').returncode == 0
    assert_enabled(project)


def test_conflicting_board_flag_is_warned_about(tmp_path):
    project = make_project(tmp_path, 'zub1cg', 'fresh')
    result = run_tool(project, '--board', 'u96v2')
    assert result.returncode == 0
    assert 'warning: the project looks like a zub1cg board' in result.stderr


@pytest.mark.parametrize('breakage, message', [
    ('no_dir', 'project directory not found'),
    ('not_project', 'not a PetaLinux project'),
    ('no_user', 'user-rootfsconfig not found'),
    ('no_rootfs', 'rootfs_config not found'),
    ('rootfs_is_dir', 'is a directory'),
    ('no_layer_conf', "the meta-user layer's layer.conf not found"),
])
def test_missing_or_unreadable_files_are_clear_errors(tmp_path, breakage, message):
    project = make_project(tmp_path, 'zub1cg', 'fresh')
    user_before = (project / USER).read_bytes()
    if breakage == 'no_dir':
        project = tmp_path / 'nowhere'
    elif breakage == 'not_project':
        shutil.rmtree(project / 'project-spec')
    elif breakage == 'no_user':
        (project / USER).unlink()
    elif breakage == 'no_rootfs':
        (project / ROOTFS).unlink()
    elif breakage == 'no_layer_conf':
        (project / LAYER_CONF).unlink()
    else:
        (project / ROOTFS).unlink()
        (project / ROOTFS).mkdir()
    for extra in ([], ['--check'], ['--dry-run']):
        result = run_tool(project, *extra)
        assert result.returncode == 2
        assert result.stderr.startswith('error: ') and message in result.stderr, result.stderr
    if breakage in ('no_rootfs', 'no_layer_conf'):  # nothing half-done
        assert (project / USER).read_bytes() == user_before
        assert not (project / META_USER / 'recipes-ros').exists()


@pytest.mark.parametrize('together', [('--check', '--dry-run'), ('--replace', '--check')])
def test_modes_that_cannot_go_together_are_a_usage_error(tmp_path, together):
    project = make_project(tmp_path, 'zub1cg', 'fresh')
    before = project_files(project)
    result = run_tool(project, *together)
    assert result.returncode == 2
    assert 'not allowed with' in result.stderr
    assert project_files(project) == before


# ---------------------------------------------------------------------------------------------
# Writing

def test_write_keeps_mode_and_follows_symlinks(tmp_path):
    project = make_project(tmp_path, 'zub1cg', 'fresh')
    real = tmp_path / 'shared-rootfs_config'
    shutil.move(str(project / ROOTFS), real)
    (project / ROOTFS).symlink_to(real)
    os.chmod(real, 0o640)
    assert run_tool(project).returncode == 0
    assert (project / ROOTFS).is_symlink()
    assert real.stat().st_mode & 0o7777 == 0o640
    assert model.assignments(real.read_bytes())['cv-bridge'] == ['y']
    assert sorted(os.listdir(tmp_path)) == ['shared-rootfs_config', 'zub1cg']


def test_a_failed_write_leaves_the_old_file_and_no_debris(tmp_path, monkeypatch):
    path = tmp_path / 'rootfs_config'
    path.write_bytes(b'# CONFIG_cv-bridge is not set\n')

    def crash(src, dst):
        raise OSError(28, 'No space left on device')

    monkeypatch.setattr(enable_ros.os, 'replace', crash)
    with pytest.raises(OSError):
        enable_ros.write_atomically(str(path), 'CONFIG_cv-bridge=y\n')
    assert path.read_bytes() == b'# CONFIG_cv-bridge is not set\n'
    assert os.listdir(tmp_path) == ['rootfs_config']


# ---------------------------------------------------------------------------------------------
# The fragments

@pytest.mark.parametrize('board', sorted(BOARDS))
def test_fragments_hold_the_ros_packages_and_obey_petalinux_rules(board):
    directory = HERE.parent / 'boards' / board
    user = (directory / 'user-rootfsconfig').read_bytes()
    rootfs = (directory / 'rootfs_config').read_bytes()
    assert model.declarations(user) == PACKAGES  # no comment that PetaLinux would misread
    assert model.assignments(rootfs) == {name: ['y'] for name in PACKAGES}
    assert model.image_packages(rootfs) == PACKAGES
    assert enable_ros.load_fragments(board) == (PACKAGES, PACKAGES)


def test_a_board_can_differ_by_editing_its_fragments(tmp_path, monkeypatch):
    boards = tmp_path / 'boards'
    shutil.copytree(HERE.parent / 'boards', boards)
    for name, line in (('user-rootfsconfig', 'CONFIG_nano\n'),
                       ('rootfs_config', 'CONFIG_nano=y\n')):
        with open(boards / 'u96v2' / name, 'a') as stream:
            stream.write(line)
    monkeypatch.setattr(enable_ros, 'BOARDS_DIR', str(boards))
    project = make_project(tmp_path, 'u96v2', 'fresh')
    assert enable_ros.main([str(project)]) == 0
    assert model.assignments((project / ROOTFS).read_bytes())['nano'] == ['y']
    assert model.declarations((project / USER).read_bytes()).count('nano') == 1
    assert_enabled(project)


@pytest.mark.parametrize('content, message', [
    ('#enable CONFIG_cv-bridge too\nCONFIG_cv-bridge\n', 'read this comment as a declaration'),
    ('CONFIG_cv_bridge\n', 'package name'),
    ('CONFIG_cv-bridge\nCONFIG_cv-bridge\n', 'listed twice'),
    ('#nothing\n', 'lists no package'),
])
def test_broken_fragments_are_refused(tmp_path, content, message):
    path = tmp_path / 'user-rootfsconfig'
    path.write_text(content)
    with pytest.raises(enable_ros.ToolError, match=message):
        enable_ros.read_fragment(str(path), 'CONFIG_{}', 'fragment')


# ---------------------------------------------------------------------------------------------
# The meta-user layer: the recipes placed, layer.conf

def test_the_layer_files_are_the_runtime_recipe_and_the_fast_dds_fix():
    found = sorted(str(path.relative_to(LAYER_SOURCE)) for path in LAYER_SOURCE.rglob('*')
                   if path.is_file())
    assert found == sorted(LAYER_FILES)
    recipe = (LAYER_SOURCE / RECIPE).read_text()
    # One plain line each: another tool reads the wheel's address and checksum from them.
    urls = re.findall(r'^SRC_URI = "(https://\S+)"$', recipe, re.M)
    sums = re.findall(r'^SRC_URI\[sha256sum\] = "([0-9a-f]{64})"$', recipe, re.M)
    assert len(urls) == 1 and len(sums) == 1, (urls, sums)
    version = re.fullmatch(r'python3-tflite-runtime_(.+)\.bb', Path(RECIPE).name).group(1)
    assert urls[0].startswith('https://files.pythonhosted.org/packages/')
    assert urls[0].endswith('/tflite_runtime-%s-cp310-cp310-manylinux_2_34_aarch64.whl' % version)
    # What bitbake makes of LICENSE, LIC_FILES_CHKSUM and COMPATIBLE_HOST: test_bitbake.py.
    assert re.search(r'^LICENSE = "Apache-2.0 & .*"$', recipe, re.M)
    assert 'file://%s;' % Path(FFT2D_LICENCE).name in recipe
    rdepends = re.search(r'^RDEPENDS:\$\{PN\} \+= "([^"]*)"$', recipe, re.M).group(1).split()
    assert {'python3-core', 'python3-numpy'} <= set(rdepends)
    # The patch is eProsima's commit as git format-patch writes it, with its upstream status.
    patch = (LAYER_SOURCE / PATCH).read_text()
    assert patch.startswith('From df904f302a443c64ea4b542e8fd486f58be50a47 ')
    assert 'Subject: [PATCH] Improve SHM resilience to crashing participants (#3765)' in patch
    assert re.search(r'^Upstream-Status: Backport \[https://github.com/eProsima/Fast-DDS/'
                     r'commit/df904f302a443c64ea4b542e8fd486f58be50a47', patch, re.M)
    bbappend = (LAYER_SOURCE / BBAPPEND).read_text()
    assert re.findall(r'^SRC_URI \+= "file://(\S+)"$', bbappend, re.M) == [
        Path(PATCH).name, Path(PATCH2).name]
    assert re.search(r'^FILESEXTRAPATHS:prepend := "\$\{THISDIR\}/files:"$', bbappend, re.M)


@pytest.mark.parametrize('recipe, applies', [
    (META_ROS_FASTRTPS, True),       # PetaLinux 2023.2's meta-ros
    ('fastrtps_2.6.0-4.bb', False),  # another release of the same sources
    ('fastrtps_2.6.7-1.bb', False),  # a Fast DDS that has the fix
    ('fastrtps_2.14.5-1.bb', False),
    ('fastrtps-cmake-module_2.2.0-2.bb', False),
])
def test_the_bbappend_takes_meta_ros_fast_dds_2_6_0_3_alone(recipe, applies):
    assert model.appends_to(Path(BBAPPEND).name, recipe) is applies
    assert enable_ros.appends_to(BBAPPEND, recipe) is applies


@pytest.mark.parametrize('board', sorted(BOARDS))
def test_a_project_with_another_copy_of_a_recipe_is_replaced_only_with_replace(tmp_path, board):
    project = make_project(tmp_path, board, 'enabled')
    old = (LAYER_SOURCE / RECIPE).read_text().replace('tflite_runtime-2.14.0-', 'x-')
    (project / META_USER / RECIPE).write_text(old)
    os.chmod(project / META_USER / RECIPE, 0o600)
    (project / META_USER / BBAPPEND).unlink()
    before = project_files(project)

    check = run_tool(project, '--check')
    assert check.returncode == 1
    assert 'meta-user: %s: differs from petalinux/meta-user/%s' % (RECIPE, RECIPE) in check.stdout
    assert 'meta-user: %s: missing' % BBAPPEND in check.stdout

    refused = run_tool(project)
    assert refused.returncode == 2
    assert refused.stderr.startswith('error: nothing written: ')
    assert '--replace' in refused.stderr
    assert project_files(project) == before  # not even the missing bbappend

    dry = run_tool(project, '--dry-run', '--replace')
    assert dry.returncode == 0
    assert '-SRC_URI = "https://files.pythonhosted.org/' in dry.stdout
    assert '/x-cp310-cp310-manylinux_2_34_aarch64.whl"' in dry.stdout
    assert 'new file %s' % (META_USER / BBAPPEND) in dry.stdout
    assert project_files(project) == before

    replaced = run_tool(project, '--replace')
    assert replaced.returncode == 0, replaced.stderr
    assert 'meta-user: placed 1 file(s), replaced 1, already %d' % (len(LAYER_FILES) - 2) in (
        replaced.stdout)
    assert_enabled(project)
    assert (project / META_USER / RECIPE).stat().st_mode & 0o777 == 0o600  # its mode kept
    assert run_tool(project).stdout.count('nothing to change') == 1
    assert run_tool(project, '--check').returncode == 0


@pytest.mark.parametrize('board', sorted(BOARDS))
def test_dry_run_shows_the_layer_files_and_check_lists_them(tmp_path, board):
    project = make_project(tmp_path, board, 'fresh')
    before = project_files(project)
    dry = run_tool(project, '--dry-run')
    assert dry.returncode == 0
    for relative in LAYER_FILES:
        assert 'new file %s (petalinux/meta-user/%s, ' % (META_USER / relative, relative) in (
            dry.stdout)
    assert 'layer.conf: BBFILES already picks up the recipes' in dry.stdout
    assert '+CONFIG_python3-tflite-runtime=y' in dry.stdout
    assert project_files(project) == before
    assert not (project / META_USER / 'recipes-ros').exists()
    check = run_tool(project, '--check')
    assert check.returncode == 1
    assert ['meta-user: %s: missing' % relative for relative in LAYER_FILES] == [
        line.strip() for line in check.stdout.splitlines() if 'meta-user: ' in line]


@pytest.mark.parametrize('layer_conf, appended', [
    # PetaLinux 2023.2's own: nothing to do.
    (None, False),
    # The same patterns through :append, and one that also reads deeper folders.
    ('BBFILES:append = " ${LAYERDIR}/recipes-*/*/*.bb ${LAYERDIR}/recipes-*/*/*.bbappend"\n',
     False),
    ('BBFILES += "${LAYERDIR}/recipes-*/*/*.bbappend"\nBBFILES += "${LAYERDIR}/recipes-*/*/*.bb '
     '${LAYERDIR}/recipes-*/*/*/*.bb"\n', False),
    # Recipes but no bbappends, only deeper folders, glued onto the earlier layers' last word.
    ('BBFILES += "${LAYERDIR}/recipes-*/*/*.bb"\n', True),
    ('BBFILES += "${LAYERDIR}/recipes-*/*/*/*.bb ${LAYERDIR}/recipes-*/*/*/*.bbappend"\n', True),
    ('BBFILES .= "${LAYERDIR}/recipes-*/*/*.bb ${LAYERDIR}/recipes-*/*/*.bbappend"\n', True),
    # Commented out.
    ('#BBFILES += "${LAYERDIR}/recipes-*/*/*.bb ${LAYERDIR}/recipes-*/*/*.bbappend"\n', True),
])
def test_layer_conf_gets_a_bbfiles_line_only_when_bitbake_would_miss_the_recipes(
        tmp_path, layer_conf, appended):
    project = make_project(tmp_path, 'zub1cg', 'fresh')
    if layer_conf is not None:
        (project / LAYER_CONF).write_text('BBPATH .= ":${LAYERDIR}"\n' + layer_conf
                                          + 'BBFILE_COLLECTIONS += "meta-user"\n')
    before = (project / LAYER_CONF).read_bytes()
    shutil.copytree(LAYER_SOURCE, project / META_USER, dirs_exist_ok=True)
    read = model.bbfiles(before, project / META_USER)
    assert (str(project / META_USER / RECIPE) in read
            and str(project / META_USER / BBAPPEND) in read) is not appended
    result = run_tool(project)
    assert result.returncode == 0, result.stderr
    after = (project / LAYER_CONF).read_bytes()
    if appended:
        assert after == before + (b'BBFILES += "${LAYERDIR}/recipes-*/*/*.bb '
                                  b'${LAYERDIR}/recipes-*/*/*.bbappend"\n')
    else:
        assert after == before
    assert_layer_in_place(project)
    assert 'nothing to change' in run_tool(project).stdout


def test_a_layer_conf_that_removes_the_pattern_is_left_to_the_user(tmp_path):
    project = make_project(tmp_path, 'u96v2', 'fresh')
    with open(project / LAYER_CONF, 'a') as stream:
        stream.write('BBFILES:remove = "${LAYERDIR}/recipes-*/*/*.bbappend"\n')
    before = project_files(project)
    for extra in ([], ['--check'], ['--dry-run']):
        result = run_tool(project, *extra)
        assert result.returncode == 2
        assert 'leaves out fastrtps_2.6.0-3.bbappend' in result.stderr
        assert 'edit it by hand' in result.stderr
    assert project_files(project) == before


def test_a_bbmask_that_hides_a_recipe_is_warned_about(tmp_path):
    project = make_project(tmp_path, 'uz7ev', 'fresh')
    with open(project / LAYER_CONF, 'a') as stream:
        stream.write('BBMASK += "meta-user/recipes-ros/"\n')
    result = run_tool(project)
    assert result.returncode == 0
    assert ("warning: %s: BBMASK 'meta-user/recipes-ros/' hides fastrtps_2.6.0-3.bbappend"
            % LAYER_CONF) in result.stderr


def test_another_version_of_a_recipe_in_the_layer_is_warned_about(tmp_path):
    project = make_project(tmp_path, 'zub1cg', 'enabled')
    other = project / META_USER / 'recipes-python/python3-tflite-runtime'
    (other / 'python3-tflite-runtime_2.15.0.bb').write_text('LICENSE = "CLOSED"\n')
    (project / META_USER / 'recipes-ros/fastrtps/fastrtps_%.bbappend').write_text('\n')
    result = run_tool(project)
    assert result.returncode == 0
    assert 'nothing to change' in result.stdout
    assert ('python3-tflite-runtime_2.15.0.bb: another version of python3-tflite-runtime, '
            'which bitbake reads too') in result.stderr
    assert 'fastrtps_%.bbappend: another bbappend of fastrtps' in result.stderr


@pytest.mark.parametrize('recipes, warned', [
    (['meta-ros2-humble/generated-recipes/fastrtps/fastrtps_2.6.0-3.bb',
      'meta-ros2-foxy/generated-recipes/fastrtps/fastrtps_2.1.1-1.bb'], False),
    (['meta-ros2-humble/generated-recipes/fastrtps/fastrtps_2.6.7-1.bb'], True),
    ([], True),
])
def test_a_meta_ros_without_fast_dds_2_6_0_3_is_warned_about(tmp_path, recipes, warned):
    project = make_project(tmp_path, 'u96v2', 'fresh')
    layers = project / 'components/yocto/layers/meta-ros'
    layers.mkdir(parents=True)
    for recipe in recipes:
        (layers / recipe).parent.mkdir(parents=True, exist_ok=True)
        (layers / recipe).write_text('\n')
    result = run_tool(project, '--check')
    message = ('warning: %s: no recipe in components/yocto/layers takes it'
               % (META_USER / BBAPPEND))
    assert (message in result.stderr) is warned, result.stderr
    if warned:
        assert 'BB_DANGLINGAPPENDS_WARNONLY' in result.stderr
        assert 'fastrtps_2.6.7-1.bb' in result.stderr or 'recipes there: none' in result.stderr


def test_new_layer_files_get_the_umask_mode(tmp_path):
    project = make_project(tmp_path, 'zub1cg', 'fresh')
    assert run_tool(project, umask=0o027).returncode == 0
    for relative in LAYER_FILES:
        assert (project / META_USER / relative).stat().st_mode & 0o777 == 0o640
    assert (project / META_USER / 'recipes-ros').stat().st_mode & 0o777 == 0o750
    assert not list(project.rglob('*.enable_ros.tmp'))


def test_a_file_where_a_layer_directory_goes_is_a_clear_error(tmp_path):
    project = make_project(tmp_path, 'zub1cg', 'fresh')
    (project / META_USER / 'recipes-ros').write_text('not a directory\n')
    before = project_files(project)
    result = run_tool(project)
    assert result.returncode == 2
    assert 'a file stands where a directory of its path should be' in result.stderr
    assert project_files(project) == before


def test_a_directory_where_a_layer_file_goes_is_a_clear_error(tmp_path):
    project = make_project(tmp_path, 'zub1cg', 'fresh')
    (project / META_USER / BBAPPEND).mkdir(parents=True)
    before = project_files(project)
    result = run_tool(project)
    assert result.returncode == 2
    assert result.stderr.startswith('error: meta-user file is a directory')
    assert project_files(project) == before
