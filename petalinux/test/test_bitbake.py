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
bitbake, the tool PetaLinux 2023.2 runs, on the recipes enable_ros.py places in a project.

../shared/yocto/yocto-langdale.tar.zst holds bitbake 2.2 and the layers PetaLinux 2023.2 builds
from: openembedded-core and meta-openembedded at langdale, Xilinx's meta-ros at rel-v2023.2
(PY_VISION_YOCTO names another copy). It is unpacked once into ~/.cache/py_vision/yocto/
(PY_VISION_YOCTO_CACHE names another place; again when the tarball changes). There, in a folder of
its own for what the tests place (meta-user, enable_ros.py and the board's skeleton: one folder per
version of them, whatever checkout or clone runs the tests), a board's project skeleton
(fixtures/zub1cg) is copied afresh and enable_ros.py run on it, and a build folder's bblayers.conf
lists those layers and the project's meta-user layer, as PetaLinux's does, but without PetaLinux's
BB_DANGLINGAPPENDS_WARNONLY: here a bbappend without its recipe is an error. MACHINE is qemuarm64
(Xilinx's layers are not there; PetaLinux's zynqmp machines are aarch64 too) and DISTRO nodistro;
as root, the sanity class, which refuses root, is left out. There is no toolchain: the tests run
what needs none, parsing, `bitbake -e`, the fetch and the licence checks (`do_patch` of the
runtime, which has no patch, is told not to build quilt).

The first parse of the 3300 recipes takes about 3 minutes on a 2-core machine alone (10 at
load 10); bitbake keeps its cache in the build folder, which stays where it is, so later runs
of the same recipes, a fresh clone's too, parse only the files enable_ros.py placed anew (10 to
50 s a command). Every bitbake command
holds the build folder's lock, so test workers, and two runs, take turns. Without the tarball,
zstd, the host tools bitbake requires (scripts/test.sh installs chrpath, diffstat, gawk and
cpio) or the en_US.UTF-8 locale these tests are skipped with the reason, and fail in CI. The
fetch needs files.pythonhosted.org.
"""

import contextlib
import fcntl
import hashlib
import os
from pathlib import Path
import re
import shutil
import subprocess
import sys
import zipfile

import pytest

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]
TOOL = REPO / 'petalinux' / 'enable_ros.py'
LAYER_SOURCE = REPO / 'petalinux' / 'meta-user'
BOARD = 'zub1cg'
# The unpacked layers, shared; the build folders, one set per version of what the tests place
# (a checkout with other recipes gets its own; a fresh clone of the same ones finds bitbake's
# cache of the last run). Not in .venv: tried there, bitbake's server (started as
# "bitbake-server", so its Python does not know its own path) loaded .venv's packages and died
# in their start-up.
CACHE = Path(os.environ.get('PY_VISION_YOCTO_CACHE') or Path(
    os.environ.get('XDG_CACHE_HOME') or Path.home() / '.cache') / 'py_vision' / 'yocto')


def _placed_version() -> str:
    """Return a digest of what the tests place: meta-user, enable_ros.py, the skeleton."""
    digest = hashlib.sha1()
    for root in (LAYER_SOURCE, TOOL, HERE / 'fixtures' / BOARD):
        files = [root] if root.is_file() else sorted(
            path for path in root.rglob('*')
            if path.is_file() and '__pycache__' not in path.parts)
        for path in files:
            digest.update(str(path.relative_to(REPO)).encode() + b'\0' + path.read_bytes())
    return digest.hexdigest()[:12]


CHECKOUT = CACHE / ('recipes-' + _placed_version())
TARBALL = 'yocto-langdale.tar.zst'
# The layers of the tarball, in bblayers.conf's order; the project's meta-user goes last.
LAYERS = ('openembedded-core/meta', 'meta-oe', 'meta-python', 'meta-networking',
          'meta-ros/meta-ros-common', 'meta-ros/meta-ros2', 'meta-ros/meta-ros2-humble')
META_USER = Path('project-spec') / 'meta-user'
RUNTIME = 'python3-tflite-runtime'
RECIPE = Path('recipes-python') / RUNTIME / ('%s_2.14.0.bb' % RUNTIME)
BBAPPEND = Path('recipes-ros') / 'fastrtps' / 'fastrtps_2.6.0-3.bbappend'
# meta-ros' recipe the bbappend is for, and its sources' revision.
FASTRTPS = 'meta-ros/meta-ros2-humble/generated-recipes/fastrtps/fastrtps_2.6.0-3.bb'
FASTRTPS_GIT = ('git://github.com/ros2-gbp/fastrtps-release;branch=release/humble/fastrtps;'
                'protocol=https')
FASTRTPS_SRCREV = '8abc213600a44e91cb16df8b7a972e603d9b7bcb'
PATCHES = ['0001-Improve-SHM-resilience-to-crashing-participants-3765.patch',
           '0002-Fix-SharedMem-self-deadlock-in-blocked-processing-re.patch']
# What the runtime's recipe means to give bitbake (its comments say why).
LICENSE = 'Apache-2.0 & BSD-3-Clause & BSD-2-Clause & MPL-2.0 & MIT & Ooura-fft2d'
GENERIC = ['Apache-2.0', 'BSD-3-Clause', 'BSD-2-Clause', 'MPL-2.0', 'MIT']
RDEPENDS = {'python3-core', 'python3-ctypes', 'python3-numpy'}
# The first parse of every recipe, and any other command (a fetch included).
PARSE_TIMEOUT, COMMAND_TIMEOUT = 3600, 1800


def _unavailable(why: str) -> None:
    if os.environ.get('CI') == 'true':
        pytest.fail(why + ', and CI requires it (scripts/test.sh sets it up)')
    pytest.skip(why)


def _tarball_in(folder: Path):
    path = folder / TARBALL
    return path if path.is_file() else None


def find_tarball():
    """Return the layers' tarball: PY_VISION_YOCTO, else ../shared/yocto as setup.sh looks."""
    named = os.environ.get('PY_VISION_YOCTO')
    if named:
        path = Path(named)
        return path if path.is_file() else _tarball_in(path)
    places = [REPO.parent / 'shared' / 'yocto']
    for command in (['rev-parse', '--path-format=absolute', '--git-common-dir'],
                    ['remote', 'get-url', 'origin']):
        result = subprocess.run(['git', '-C', str(REPO)] + command, capture_output=True,
                                text=True)
        if result.returncode == 0 and result.stdout.strip():
            found = Path(REPO, result.stdout.strip().replace('file://', '', 1))
            places.append((found.parent if command[0] == 'rev-parse' else found).parent
                          / 'shared' / 'yocto')
    for place in places:
        if _tarball_in(place):
            return _tarball_in(place)
    return None


def unpack(tarball: Path) -> Path:
    """Unpack the tarball into the cache (once per tarball); return the folder."""
    digest = hashlib.sha1(tarball.read_bytes()).hexdigest()[:12]
    root = CACHE / ('langdale-' + digest)
    if (root / '.unpacked').is_file():
        return root
    if shutil.which('zstd') is None:
        _unavailable('zstd is missing, to unpack %s (Debian: zstd)' % tarball)
    shutil.rmtree(root, ignore_errors=True)
    part = CACHE / ('.unpacking-' + digest)
    shutil.rmtree(part, ignore_errors=True)
    part.mkdir(parents=True)
    subprocess.run('zstd -dc "%s" | tar -x -C "%s"' % (tarball, part), shell=True, check=True,
                   timeout=600)
    (part / '.unpacked').write_text(str(tarball) + '\n')
    part.rename(root)
    return root


def bitbake_env(yocto: Path) -> dict:
    """Return the environment bitbake runs in: its locale, its bin/ first, no virtualenv."""
    path = [str(yocto / 'bitbake' / 'bin')] + [
        p for p in os.environ.get('PATH', '/usr/bin:/bin').split(os.pathsep)
        if p and not (Path(p).parent / 'pyvenv.cfg').is_file()]
    env = {key: value for key, value in os.environ.items()
           if not key.startswith(('BB', 'PYTHON', 'VIRTUAL_ENV'))}
    env.update(LANG='en_US.UTF-8', LC_ALL='en_US.UTF-8', PATH=os.pathsep.join(path))
    return env


def parse_env(output: str) -> dict:
    """Return the variables of a `bitbake -e` output (VAR="value" lines)."""
    found = {}
    for match in re.finditer(r'^(?:export )?([A-Za-z0-9_:${}.+/-]+)="(.*)"$', output, re.M):
        found[match.group(1)] = match.group(2).replace('\\"', '"').replace('\\$', '$')
    return found


class Build:
    """A build folder for the tarball's layers and a project's meta-user layer."""

    def __init__(self, yocto: Path, project: Path):
        self.yocto = yocto
        self.project = project
        self.meta_user = project / META_USER
        self.folder = CHECKOUT / 'build'
        self.downloads = CHECKOUT / 'downloads'

    def write_conf(self, folder: Path, extra: str = '') -> None:
        """Write folder's conf/bblayers.conf and conf/local.conf (extra: more settings)."""
        (folder / 'conf').mkdir(parents=True, exist_ok=True)
        layers = ''.join('    %s \\\n' % (self.yocto / 'layers' / name) for name in LAYERS)
        (folder / 'conf' / 'bblayers.conf').write_text(
            'LCONF_VERSION = "7"\nBBPATH = "${TOPDIR}"\nBBFILES ?= ""\n'
            'BBLAYERS = " \\\n%s    %s \\\n"\n' % (layers, self.meta_user))
        local = ('MACHINE ?= "qemuarm64"\nDISTRO = ""\nCONF_VERSION = "2"\n'
                 'DL_DIR = "%s"\n' % self.downloads)
        if os.geteuid() == 0:
            local += '# The sanity checks refuse to run as root.\nINHERIT:remove = "sanity"\n'
        # No toolchain here: the runtime's recipe has no patch, so its do_patch needs neither
        # quilt-native nor patch-native (which would be built from source first).
        local += ('PATCHDEPENDENCY:remove:pn-%s = "quilt-native:do_populate_sysroot '
                  'patch-replacement-native:do_populate_sysroot"\n' % RUNTIME)
        (folder / 'conf' / 'local.conf').write_text(extra + local)

    def bitbake(self, *args, folder=None, timeout=COMMAND_TIMEOUT):
        """Run bitbake in the build folder (or another); return the CompletedProcess."""
        folder = folder or self.folder
        result = subprocess.run(
            [str(self.yocto / 'bitbake' / 'bin' / 'bitbake')] + list(args), cwd=folder,
            env=dict(bitbake_env(self.yocto), BBPATH=str(folder)), capture_output=True,
            text=True, timeout=timeout)
        result.output = result.stdout + result.stderr
        # What bitbake says when the host lacks what it needs (not in `bitbake -e`'s output,
        # which holds the code that says it).
        for missing in (r'^ERROR: The following required tools \(as specified by HOSTTOOLS\) '
                        r'appear to be unavailable in PATH[^\n]*\n\s*([^\n]*)',
                        r"^(Please make sure locale 'en_US.UTF-8' is available[^\n]*)",
                        r'^(Please use a locale setting which supports UTF-8[^\n]*)'):
            found = re.search(missing, result.stderr if '-e' in args else result.output, re.M)
            if found:
                _unavailable('bitbake cannot run here: %s' % found.group(1).strip())
        return result

    def env(self, recipe: str) -> dict:
        result = self.bitbake('-e', recipe)
        assert result.returncode == 0, describe(result)
        return parse_env(result.stdout)


def describe(result) -> str:
    """Return a failed bitbake command's lines that say why (its ERROR lines and the end)."""
    lines = result.output.splitlines()
    errors = [line for line in lines if line.startswith(('ERROR', 'WARNING'))]
    return 'bitbake %s: exit status %d\n%s\n--- last lines:\n%s' % (
        ' '.join(result.args[1:]), result.returncode, '\n'.join(errors[:40]),
        '\n'.join(lines[-40:]))


_held = []


@contextlib.contextmanager
def locked(folder=CHECKOUT):
    """Hold the lock of a folder of the cache: one bitbake at a time there, whatever the run."""
    if _held:  # this process holds it already (a fixture inside a test that holds it)
        yield
        return
    folder.mkdir(parents=True, exist_ok=True)
    with open(folder / 'lock', 'w') as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        _held.append(lock)
        try:
            yield
        finally:
            _held.pop()
            fcntl.flock(lock, fcntl.LOCK_UN)


@pytest.fixture(scope='module')
def build():
    """Set up the build folder on a project enable_ros.py has just been run on, and parse."""
    tarball = find_tarball()
    if tarball is None:
        _unavailable('no %s in ../shared/yocto (PY_VISION_YOCTO names another)' % TARBALL)
    with locked(CACHE):
        yocto = unpack(tarball)
    with locked():
        # A project at the same place every run: bitbake's cache then stays valid for the
        # layers, and only the placed files, new every run, are parsed again.
        project = CHECKOUT / 'project' / BOARD
        shutil.rmtree(project.parent, ignore_errors=True)
        shutil.copytree(HERE / 'fixtures' / BOARD, project)
        placed = subprocess.run([sys.executable, str(TOOL), str(project)], capture_output=True,
                                text=True, timeout=120)
        assert placed.returncode == 0, placed.stdout + placed.stderr
        setup = Build(yocto, project)
        setup.write_conf(setup.folder)
        setup.parse = setup.bitbake('-p', timeout=PARSE_TIMEOUT)
    return setup


@pytest.fixture
def bb(build):
    """Give a test the build, holding the lock throughout the test."""
    with locked():
        yield build


@contextlib.contextmanager
def changed(path: Path, old: str, new: str):
    """Replace old by new in a file of the project for the block, then put it back."""
    text = path.read_text()
    assert old in text, (path, old)
    path.write_text(text.replace(old, new))
    try:
        yield
    finally:
        path.write_text(text)


def test_every_recipe_parses_and_every_bbappend_finds_its_recipe(bb):
    # The layers and the placed files, under bitbake -p: no error, dangling appends included.
    assert bb.parse.returncode == 0, describe(bb.parse)
    summary = re.search(r'Parsing of (\d+) \.bb files complete .* (\d+) errors', bb.parse.output)
    assert summary and int(summary.group(1)) > 3000 and summary.group(2) == '0', bb.parse.output
    for relative in (RECIPE, BBAPPEND):
        assert (bb.meta_user / relative).read_bytes() == (LAYER_SOURCE / relative).read_bytes()


def test_a_bbappend_without_its_recipe_is_an_error_here(bb):
    # What a meta-ros with another Fast DDS would do to the bbappend: fail, not warn.
    stray = bb.meta_user / BBAPPEND.with_name('fastrtps_2.6.0-4.bbappend')
    shutil.copyfile(bb.meta_user / BBAPPEND, stray)
    try:
        result = bb.bitbake('-p')
    finally:
        stray.unlink()
    assert result.returncode != 0, describe(result)
    assert re.search(r'ERROR: No recipes in default available for:\s+%s' % re.escape(str(stray)),
                     result.output), describe(result)


def test_fast_dds_is_meta_ros_recipe_with_both_patches_in_order(bb):
    env = bb.env('fastrtps')
    assert env['FILE'] == str(bb.yocto / 'layers' / FASTRTPS)
    assert str(bb.meta_user / BBAPPEND) in env['BBINCLUDED'].split()
    assert env['PV'] == '2.6.0-3' and env['SRCREV'] == FASTRTPS_SRCREV
    assert env['SRC_URI'].split() == [FASTRTPS_GIT] + ['file://' + name for name in PATCHES]
    # The fetcher looks for file:// entries along FILESPATH: the placed patches come first.
    files = bb.meta_user / BBAPPEND.parent / 'files'
    for name in PATCHES:
        found = next(Path(folder) / name for folder in env['FILESPATH'].split(':')
                     if (Path(folder) / name).is_file())
        assert found == files / name
        assert found.read_bytes() == (LAYER_SOURCE / BBAPPEND.parent / 'files' / name).read_bytes()
    # The bbappend changes the sources alone: meta-ros' licence and run-time dependencies stay.
    assert env['LICENSE'] == 'Apache-2.0'
    assert set(env['RDEPENDS:fastrtps'].split()) == {
        'fastcdr', 'foonathan-memory-vendor', 'libtinyxml2', 'openssl'}


def test_the_runtime_recipe_gives_bitbake_what_it_intends(bb):
    env = bb.env(RUNTIME)
    recipe = (LAYER_SOURCE / RECIPE).read_text()
    url = re.search(r'^SRC_URI = "(\S+)"$', recipe, re.M).group(1)
    assert env['FILE'] == str(bb.meta_user / RECIPE)
    assert env['SRC_URI'].split() == [url, 'file://readme2d.txt']
    assert env['LICENSE'] == LICENSE
    chksums = env['LIC_FILES_CHKSUM'].split()
    assert [entry.split(';')[0] for entry in chksums] == [
        'file://%s/%s' % (env['COMMON_LICENSE_DIR'], name) for name in GENERIC] + [
        'file://readme2d.txt']
    assert set(env['RDEPENDS:%s' % RUNTIME].split()) == RDEPENDS
    assert env['COMPATIBLE_HOST'] == 'aarch64-.*-linux'
    assert env['PYTHON_BASEVERSION'] == '3.10'


@pytest.fixture(scope='module')
def fetched(build, tmp_path_factory):
    """
    Fetch the wheel afresh (cleanall first), unpack it, run the licence checks: what came out.

    Looked at under the lock, before another test cleans the recipe's files away.
    """
    recipe = (LAYER_SOURCE / RECIPE).read_text()
    url = re.search(r'^SRC_URI = "(\S+)"$', recipe, re.M).group(1)
    wheel = url.rsplit('/', 1)[1]
    with locked():
        # What a fetch stopped by a wrong checksum, or killed, left behind (wget's .tmp, a
        # _bad-checksum_ copy) is no download cleanall knows of: it goes first.
        for leftover in build.downloads.glob(wheel + '?*'):
            if not leftover.name.endswith('.done'):
                leftover.unlink()
        clean = build.bitbake('-c', 'cleanall', RUNTIME)
        assert clean.returncode == 0, describe(clean)
        assert not list(build.downloads.glob(wheel + '*'))
        result = build.bitbake('-c', 'populate_lic', RUNTIME)
        env = build.env(RUNTIME)
        workdir = Path(env['WORKDIR'])
        downloaded, done = build.downloads / wheel, build.downloads / (wheel + '.done')
        licences = Path(env['LICSSTATEDIR']) / RUNTIME
        seen = {
            'result': result,
            'sha256': downloaded.is_file() and hashlib.sha256(
                downloaded.read_bytes()).hexdigest(),
            'stamp': done.read_bytes() if done.is_file() else b'',
            'unpacked': (workdir / wheel).is_file() and downloaded.is_file() and (
                workdir / wheel).read_bytes() == downloaded.read_bytes(),
            'readme2d.txt': (workdir / 'readme2d.txt').is_file() and (
                workdir / 'readme2d.txt').read_bytes(),
            'licences': sorted(p.name for p in licences.glob('generic_*')),
            'fft2d licence': (licences / 'generic_Ooura-fft2d').is_file() and (
                licences / 'generic_Ooura-fft2d').read_text(),
            'wheel': None,
            'install': build.yocto / 'layers' / 'openembedded-core' / 'meta' /
            'classes-recipe' / 'python_pep517.bbclass',
        }
        if (workdir / wheel).is_file():  # kept for the install test, as the fetcher gave it
            seen['wheel'] = tmp_path_factory.mktemp('wheel') / wheel
            shutil.copyfile(workdir / wheel, seen['wheel'])
    return seen


def test_bitbake_fetches_the_wheel_checks_its_sha256_and_unpacks_it(fetched):
    result = fetched['result']
    assert result.returncode == 0, describe(result)
    sha256 = re.search(r'^SRC_URI\[sha256sum\] = "(\w+)"$', (LAYER_SOURCE / RECIPE).read_text(),
                       re.M).group(1)
    assert re.search(r'do_fetch: Succeeded', result.output), describe(result)
    assert fetched['sha256'] == sha256
    # The fetcher's stamp keeps the checksums it checked the download against.
    assert sha256.encode() in fetched['stamp']
    # Unpacked: a .whl, which the fetcher does not open, is copied into WORKDIR as it is.
    assert fetched['unpacked']
    assert fetched['readme2d.txt'] == (
        LAYER_SOURCE / RECIPE.parent / 'files' / 'readme2d.txt').read_bytes()


def test_the_image_gets_the_wheels_files_as_the_readme_says(fetched, tmp_path):
    # langdale's python_pep517 installs the wheel with pypa/installer 0.5.1 (its
    # python3-installer), with the options its do_install gives; OE's one patch to installer
    # (--interpreter) writes scripts' first lines, and this wheel has no script.
    assert fetched['wheel'] is not None, 'the fetch test failed: no wheel to install'
    line = next(line for line in fetched['install'].read_text().splitlines()
                if '-m installer' in line)
    level = re.search(r'^INSTALL_WHEEL_COMPILE_BYTECODE \?= "(.*)"$',
                      fetched['install'].read_text(), re.M).group(1)
    assert '${INSTALL_WHEEL_COMPILE_BYTECODE}' in line and '--destdir=${D}' in line, line
    import installer
    assert installer.__version__ == '0.5.1'
    with zipfile.ZipFile(fetched['wheel']) as wheel:
        inside = {name: wheel.read(name) for name in wheel.namelist()}
    assert not [name for name in inside if '.data/scripts/' in name or
                name.endswith('entry_points.txt')]
    destdir = tmp_path / 'image'
    run = subprocess.run([sys.executable, '-m', 'installer', level, '--destdir=%s' % destdir,
                          str(fetched['wheel'])], capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stdout + run.stderr
    site = next(destdir.rglob('site-packages'))
    installed = sorted(str(path.relative_to(site)) for path in site.rglob('*') if path.is_file())
    # Compiled by the Python that runs installer: the image's build host compiles them with
    # its Python 3.10 (cpython-310, as petalinux/README.md says); here with this one's.
    tag = 'cpython-%d%d' % sys.version_info[:2]
    modules = ['__init__', 'interpreter', 'metrics_interface', 'metrics_portable']
    info = 'tflite_runtime-2.14.0.dist-info/'
    assert installed == sorted(
        ['tflite_runtime/%s.py' % name for name in modules]
        + ['tflite_runtime/__pycache__/%s.%s.pyc' % (name, tag) for name in modules]
        + ['tflite_runtime/_pywrap_tensorflow_interpreter_wrapper.so']
        + [info + name for name in ('METADATA', 'WHEEL', 'top_level.txt', 'RECORD')])
    # The modules, the extension module and the metadata: byte for byte the wheel's.
    for name in installed:
        if not name.endswith(('.pyc', 'RECORD')):
            assert (site / name).read_bytes() == inside[name], name
    # RECORD rewritten: every file but the .pyc, its sha256 in hexadecimal, as `ls` sees them.
    record = {}
    for row in (site / info / 'RECORD').read_text().splitlines():
        path, digest, size = row.rsplit(',', 2)
        record[path] = digest
    assert sorted(record) == sorted(name for name in installed if not name.endswith('.pyc'))
    for path, digest in record.items():
        if path.endswith('RECORD'):
            assert digest == ''
        else:
            assert digest == 'sha256=' + hashlib.sha256((site / path).read_bytes()).hexdigest()


def test_oe_licence_checks_pass_the_runtime_recipe(fetched):
    result = fetched['result']
    assert result.returncode == 0, describe(result)
    assert 'do_populate_lic: Succeeded' in result.output, describe(result)
    assert not re.search(r'^(WARNING|ERROR):.*%s' % RUNTIME, result.output, re.M), describe(
        result)
    assert fetched['licences'] == sorted(
        'generic_' + name for name in GENERIC + ['Ooura-fft2d'])
    assert 'Takuya OOURA' in fetched['fft2d licence']


def test_a_wrong_sha256_stops_the_fetch(bb, fetched):
    recipe = bb.meta_user / RECIPE
    sha256 = re.search(r'^SRC_URI\[sha256sum\] = "(\w+)"$', recipe.read_text(), re.M).group(1)
    wrong = hashlib.sha256(b'not the wheel').hexdigest()
    wheel = re.search(r'^SRC_URI = "\S+/(\S+)"$', recipe.read_text(), re.M).group(1)
    with changed(recipe, sha256, wrong):
        assert bb.bitbake('-c', 'cleanall', RUNTIME).returncode == 0  # a download, not a copy
        result = bb.bitbake('-c', 'fetch', RUNTIME)
    # The refused download stays nowhere a later fetch would take it from.
    for leftover in bb.downloads.glob(wheel + '*'):
        leftover.unlink()
    assert result.returncode != 0, describe(result)
    assert 'Checksum mismatch' in result.output, describe(result)
    assert wrong in result.output and sha256 in result.output, describe(result)


def test_a_licence_text_that_changed_fails_the_licence_check(bb, fetched):
    recipe = bb.meta_user / RECIPE
    md5 = re.search(r'file://readme2d\.txt;[^"\s]*md5=(\w+)', recipe.read_text()).group(1)
    with changed(recipe, 'md5=' + md5, 'md5=' + '0' * 32):
        result = bb.bitbake('-c', 'populate_lic', RUNTIME)
    assert result.returncode != 0, describe(result)
    assert re.search(r'The LIC_FILES_CHKSUM does not match for file://readme2d\.txt',
                     result.output), describe(result)
    assert 'The new md5 checksum is %s' % md5 in result.output, describe(result)


@pytest.mark.parametrize('name, setting, host', [
    ('aarch64', '', None),
    ('aarch64_be', 'DEFAULTTUNE = "aarch64_be"\n', 'aarch64_be-oe-linux'),
    ('musl', 'TCLIBC = "musl"\n', 'aarch64-oe-linux-musl'),
    ('x86-64', 'MACHINE = "qemux86-64"\n', 'x86_64-oe-linux'),
])
def test_the_runtime_builds_for_little_endian_aarch64_with_glibc_alone(bb, name, setting, host):
    # bitbake -b reads this recipe alone: another host costs no parse of the others.
    folder = CHECKOUT / ('build-' + name)
    bb.write_conf(folder, setting)
    result = bb.bitbake('-n', '-b', str(bb.meta_user / RECIPE), '-c', 'fetch', folder=folder)
    if host is None:
        assert result.returncode == 0, describe(result)
    else:
        assert result.returncode != 0, describe(result)
        assert 'was skipped: incompatible with host %s (not in COMPATIBLE_HOST)' % host in (
            result.output), describe(result)
