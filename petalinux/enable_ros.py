#!/usr/bin/env python3
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
Put into a PetaLinux 2023.2 project what py_vision needs in the board's image.

Usage: python3 petalinux/enable_ros.py PROJECT_DIR [--board B] [--check | --dry-run] [--replace]

The package lists come from petalinux/boards/<board>/user-rootfsconfig (declarations) and
petalinux/boards/<board>/rootfs_config (enabled packages): the tutorial's ROS 2 packages, the
Python modules py_vision imports (OpenCV, numpy, PyYAML, the TensorFlow Lite runtime), xauth
for ssh -X windows and vision-msgs (the faces step's detections). The recipes PetaLinux does
not have come from petalinux/meta-user/: the TensorFlow Lite runtime's, and a bbappend that
patches meta-ros' Fast DDS 2.6.0. The tool edits three project files and places those, keeping
every byte it has no reason to touch:

- project-spec/meta-user/conf/user-rootfsconfig: PetaLinux reads every line that contains
  the config prefix as a declaration (comments too) and takes the name up to the next
  underscore. Each package ends up declared by exactly one plain line; a commented-out or
  padded declaration of it is turned into that line in place, repeats are removed, missing
  ones are appended (after giving the last line its newline).
- project-spec/configs/rootfs_config (Kconfig output): each package ends up with exactly one
  assignment, which is the exact '=y' line. The first existing assignment ('is not set',
  '=n', '=m', '=y ' with a trailing space...) is rewritten in place; further assignments,
  which Kconfig would apply after it (the last one wins), are removed; a package with no
  assignment is inserted in sorted position in the 'user packages' block, or appended at
  the end of the file when there is no such block.
- project-spec/meta-user/: each file of petalinux/meta-user/ at the same place. A missing one
  is copied; one that is there with other content (an older copy, or your own edit) is
  replaced only with --replace, and without it nothing at all is written.
- project-spec/meta-user/conf/layer.conf: left as it is when its BBFILES already picks up the
  recipes placed (PetaLinux's own does); otherwise one BBFILES line is appended.

Writes are atomic (temporary file in the same directory, fsync, rename), keep the file mode
and go through symlinks to their target; new files get the mode your umask gives. Running the
tool again changes nothing. Exit status: 0 done (or --check: nothing missing), 1 --check:
something is missing or differs, 2 bad usage, missing project or file, unknown board,
unreadable or unwritable file, a layer file that differs without --replace.
"""

import argparse
import difflib
import fnmatch
import os
import re
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
BOARDS_DIR = os.path.join(HERE, 'boards')

# The files of a layer that the tool places in the project's meta-user layer.
LAYER_SOURCE = os.path.join(HERE, 'meta-user')

META_USER = os.path.join('project-spec', 'meta-user')
USER_ROOTFSCONFIG = os.path.join(META_USER, 'conf', 'user-rootfsconfig')
LAYER_CONF = os.path.join(META_USER, 'conf', 'layer.conf')
ROOTFS_CONFIG = os.path.join('project-spec', 'configs', 'rootfs_config')
PROJECT_CONFIG = os.path.join('project-spec', 'configs', 'config')
# Where PetaLinux 2023.2 keeps the Yocto layers (meta-ros among them), once it has set them up.
YOCTO_LAYERS = os.path.join('components', 'yocto', 'layers')
# What PetaLinux 2023.2's own meta-user/conf/layer.conf gives BBFILES, appended to a layer.conf
# whose BBFILES does not pick up the recipes the tool places.
BBFILES_LINE = 'BBFILES += "${LAYERDIR}/recipes-*/*/*.bb ${LAYERDIR}/recipes-*/*/*.bbappend"'

# board id -> (what it is, the hostname of the tutorial's project, strings that identify it in
# the project's settings once lower-cased and stripped of '-', '_' and '.')
BOARDS = {
    'zub1cg': ('ZUBoard 1CG', 'zub1cg-sbc-2023-2', ('zub1cg',)),
    'u96v2': ('Ultra96-V2', 'u96v2-sbc-2023-2', ('u96v2', 'ultra96v2')),
    'uz7ev': ('UltraZed-7EV with its EV carrier card', 'uz7ev-evcc-2023-2', ('uz7ev',)),
}
# The settings of project-spec/configs/config that name the board, most telling first.
DETECTION_KEYS = ('CONFIG_SUBSYSTEM_HOSTNAME', 'CONFIG_SUBSYSTEM_PRODUCT',
                  'CONFIG_YOCTO_MACHINE_NAME')

# A package name PetaLinux keeps whole: no underscore (it cuts the name there), no blanks.
PACKAGE_NAME = re.compile(r'[A-Za-z0-9][A-Za-z0-9.+-]*\Z')

NEXT_STEPS = """\
Next steps:
  in the PetaLinux project:
    petalinux-config -c rootfs --silentconfig
    petalinux-build
  then on the board (after booting the new image):
    source /usr/bin/ros_setup.sh
    cd ~/vision_ws && colcon build && source install/local_setup.sh
    ros2 run py_vision usbcam_publisher"""


class ToolError(Exception):
    """A problem the user must fix: reported as one message, exit status 2."""


# ---------------------------------------------------------------------------------------------
# Lines that keep their bytes

class Line:
    """One line of a file: its text and its end of line (LF, CRLF, or none at the very end)."""

    __slots__ = ('text', 'eol', 'number')

    def __init__(self, text, eol, number=None):
        self.text = text
        self.eol = eol
        self.number = number  # 1-based line number in the original file, None for new lines


def split_lines(data):
    """Split decoded file content into Lines; only LF ends a line, as for Kconfig."""
    lines = []
    for number, chunk in enumerate(re.findall(r'[^\n]*\n|[^\n]+\Z', data), start=1):
        if chunk.endswith('\r\n'):
            lines.append(Line(chunk[:-2], '\r\n', number))
        elif chunk.endswith('\n'):
            lines.append(Line(chunk[:-1], '\n', number))
        else:
            lines.append(Line(chunk, '', number))
    return lines


def join_lines(lines):
    """Return the file content of Lines (None entries are deleted lines)."""
    return ''.join(line.text + line.eol for line in lines if line is not None)


def file_eol(lines):
    """Return the end of line the file already uses, LF for an empty or one-line file."""
    for line in lines:
        if line.eol:
            return line.eol
    return '\n'


def insert_line(lines, index, text, eol):
    """Insert a new line before lines[index], giving the last line its end of line first."""
    if index == len(lines) and lines and not lines[-1].eol:
        lines[-1].eol = eol
    lines.insert(index, Line(text, eol))


def read_text(path, what):
    """Read a file as text that maps back to the very same bytes (undecodable ones too)."""
    try:
        with open(path, 'rb') as stream:
            return stream.read().decode('utf-8', 'surrogateescape')
    except FileNotFoundError:
        raise ToolError('%s not found: %s' % (what, path))
    except IsADirectoryError:
        raise ToolError('%s is a directory, expected a file: %s' % (what, path))
    except OSError as error:
        raise ToolError('cannot read %s %s: %s' % (what, path, error.strerror or error))


def read_bytes(path, what):
    """Return a file's bytes, or None when there is no such file."""
    try:
        with open(path, 'rb') as stream:
            return stream.read()
    except FileNotFoundError:
        return None
    except IsADirectoryError:
        raise ToolError('%s is a directory, expected a file: %s' % (what, path))
    except NotADirectoryError:
        raise ToolError('%s cannot be placed: a file stands where a directory of its path '
                        'should be: %s' % (what, path))
    except OSError as error:
        raise ToolError('cannot read %s %s: %s' % (what, path, error.strerror or error))


def new_file_mode():
    """Return the mode a new file gets from the umask, as cp or an editor would give it."""
    umask = os.umask(0o022)
    os.umask(umask)
    return 0o666 & ~umask


def write_atomically(path, content):
    """
    Write a file (text or bytes) so that a crash leaves either the old or the new file.

    An existing file keeps its mode; a new one gets new_file_mode() and its directories are
    made. A symlink's target is written, not the link.
    """
    target = os.path.realpath(path)
    directory = os.path.dirname(target)
    if os.path.exists(target):
        mode = os.stat(target).st_mode & 0o7777
    else:
        mode = new_file_mode()
        os.makedirs(directory, exist_ok=True)
    if isinstance(content, str):
        content = content.encode('utf-8', 'surrogateescape')
    fd, temporary = tempfile.mkstemp(prefix='.%s.' % os.path.basename(target),
                                     suffix='.enable_ros.tmp', dir=directory)
    try:
        with os.fdopen(fd, 'wb') as stream:
            stream.write(content)
            stream.flush()
            os.fsync(stream.fileno())
        os.chmod(temporary, mode)
        os.replace(temporary, target)
    except BaseException:
        try:
            os.unlink(temporary)
        except OSError:
            pass
        raise
    try:  # make the rename itself durable; not every file system lets a directory be opened
        dir_fd = os.open(directory, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(dir_fd)
    except OSError:
        pass
    finally:
        os.close(dir_fd)


# ---------------------------------------------------------------------------------------------
# How PetaLinux and Kconfig read the two files

def petalinux_declaration(text):
    """
    Return the package name PetaLinux reads from a user-rootfsconfig line, or None.

    PetaLinux takes every line containing 'CONFIG_' (comments included), formats it as a
    one-element Python list and keeps what lies between the first underscore and the next
    underscore or quote.
    """
    quoted = str([text])
    if 'CONFIG_' not in quoted:
        return None
    return quoted.split('_')[1].split("'")[0]


def kconfig_assignment(text):
    """
    Return (symbol, value) when Kconfig reads the line as an assignment, else None.

    Kconfig reads 'CONFIG_<sym>=<value>' (value up to the end of line, blanks included) and
    '#?CONFIG_<sym> is not set', which assigns 'n'. Everything else is a comment.
    """
    if text.startswith('CONFIG_'):
        symbol, equals, value = text[len('CONFIG_'):].partition('=')
        if equals:
            return symbol, value
        return None
    match = re.match(r'#.CONFIG_([^ ]*) is not set', text)
    if match:
        return match.group(1), None
    return None


# ---------------------------------------------------------------------------------------------
# The board and its fragments

def board_choices():
    """Return the board ids as the usage text lists them."""
    return '|'.join(BOARDS)


def read_kconfig_strings(text):
    """Return the string settings of a Kconfig file ('CONFIG_X="value"') as a dict."""
    settings = {}
    for line in split_lines(text):
        match = re.match(r'(CONFIG_[A-Za-z0-9_]+)="((?:[^"\\]|\\.)*)"\s*\Z', line.text)
        if match:
            settings[match.group(1)] = re.sub(r'\\(.)', r'\1', match.group(2))
    return settings


def boards_named_by(value):
    """Return the board ids whose identifying strings appear in a setting's value."""
    flat = re.sub(r'[-_.\s]', '', value.lower())
    return [board for board, (_, _, keys) in BOARDS.items() if any(k in flat for k in keys)]


def detect_board(project):
    """Return (board id, reason) from project-spec/configs/config, or raise ToolError."""
    path = os.path.join(project, PROJECT_CONFIG)
    try:
        settings = read_kconfig_strings(read_text(path, 'PetaLinux project settings'))
    except ToolError as error:
        raise ToolError('%s; cannot tell the board, pass --board %s'
                        % (error, board_choices()))
    found = []
    for key in DETECTION_KEYS:
        if key in settings:
            for board in boards_named_by(settings[key]):
                found.append((board, '%s="%s"' % (key, settings[key])))
    boards = sorted({board for board, _ in found})
    if len(boards) == 1:
        return found[0]
    seen = ', '.join('%s="%s"' % (key, settings[key]) for key in DETECTION_KEYS
                     if key in settings) or 'none of %s' % ', '.join(DETECTION_KEYS)
    if not boards:
        raise ToolError('cannot tell the board from %s (%s); pass --board %s'
                        % (path, seen, board_choices()))
    raise ToolError('%s names more than one board (%s: %s); pass --board %s'
                    % (path, ', '.join(boards), seen, board_choices()))


def read_fragment(path, line_format, what):
    """Return the package names of a fragment: one line_format line ('CONFIG_{}') each."""
    prefix, suffix = line_format.split('{}')
    names = []
    for line in split_lines(read_text(path, what)):
        text = line.text
        if not text.strip():
            continue
        if text.lstrip().startswith('#'):
            if 'CONFIG_' in text:
                raise ToolError('%s:%d: PetaLinux would read this comment as a declaration '
                                '(it contains CONFIG_): %r' % (path, line.number, text))
            continue
        name = text[len(prefix):len(text) - len(suffix)]
        if not (text.startswith(prefix) and text.endswith(suffix) and PACKAGE_NAME.match(name)):
            raise ToolError('%s:%d: expected %r with a package name made of letters, digits, '
                            "'.', '+' and '-', got %r"
                            % (path, line.number, line_format.format('<name>'), text))
        if name in names:
            raise ToolError('%s:%d: %s is listed twice' % (path, line.number, name))
        names.append(name)
    if not names:
        raise ToolError('%s lists no package' % path)
    return names


def load_fragments(board):
    """Return (names to declare, names to enable) from the board's fragment files."""
    directory = os.path.join(BOARDS_DIR, board)
    if not os.path.isdir(directory):
        raise ToolError('no fragments for board %s: %s is missing' % (board, directory))
    declare = read_fragment(os.path.join(directory, 'user-rootfsconfig'), 'CONFIG_{}',
                            'the user-rootfsconfig fragment')
    enable = read_fragment(os.path.join(directory, 'rootfs_config'), 'CONFIG_{}=y',
                           'the rootfs_config fragment')
    return declare, enable


# ---------------------------------------------------------------------------------------------
# The edits

class Plan:
    """What applying the fragments does to one file: the new text and the reasons."""

    def __init__(self, label, path, old_text):
        self.label = label
        self.path = path
        self.old_text = old_text
        self.new_text = old_text
        self.done = []      # names declared / enabled by this run
        self.already = []   # names that were declared / enabled before (maybe with repeats)
        self.removed = 0    # repeated lines removed
        self.fixes = []     # (name, what is wrong, what the tool does about it)
        self.warnings = []  # problems with other lines, which the tool leaves alone

    @property
    def changed(self):
        """Return whether the file content changes."""
        return self.new_text != self.old_text

    def remove(self, lines, index, name, problem):
        """Delete lines[index] (set it to None), a repeat of name's line."""
        self.fixes.append((name, 'line %d %s: %r' % (lines[index].number, problem,
                                                     lines[index].text), 'removed that line'))
        self.removed += 1
        lines[index] = None


def plan_declarations(path, text, names):
    """Plan user-rootfsconfig: every name declared by exactly one 'CONFIG_<name>' line."""
    plan = Plan('user-rootfsconfig', path, text)
    lines = split_lines(text)
    eol = file_eol(lines)
    for name in names:
        exact = 'CONFIG_' + name
        loose = re.compile(r'[ \t]*#*[ \t]*CONFIG_%s[ \t]*\Z' % re.escape(name))
        found = [i for i, line in enumerate(lines) if loose.match(line.text)]
        if not found:
            plan.fixes.append((name, 'not declared', 'appended %r' % exact))
            plan.done.append(name)
            insert_line(lines, len(lines), exact, eol)
            continue
        keep = next((i for i in found if lines[i].text == exact), found[0])
        if lines[keep].text != exact:
            plan.fixes.append((name, 'line %d reads %r' % (lines[keep].number, lines[keep].text),
                               'made it %r in place' % exact))
            plan.done.append(name)
            lines[keep].text = exact
        else:
            plan.already.append(name)
        for i in found:
            if i != keep:
                plan.remove(lines, i, name, 'declares it again')
        lines = [line for line in lines if line is not None]
    for line in lines:
        if line.number is None or 'CONFIG_' not in line.text:
            continue
        declared = petalinux_declaration(line.text)
        if line.text.lstrip().startswith('#'):
            plan.warnings.append(
                'line %d %r is a comment, but PetaLinux still reads it as declaring %r'
                % (line.number, line.text, declared))
        elif line.text != 'CONFIG_' + declared or not PACKAGE_NAME.match(declared):
            plan.warnings.append('line %d %r: PetaLinux reads it as declaring %r'
                                 % (line.number, line.text, declared))
    plan.new_text = join_lines(lines)
    return plan


def user_packages_block(lines):
    """Return (first, end) of the entries under the '# user packages' banner, or None."""
    for i, line in enumerate(lines):
        if re.match(r'# user packages\s*\Z', line.text):
            first = i + 1
            if first < len(lines) and lines[first].text == '#':
                first += 1
            end = first
            while end < len(lines) and kconfig_assignment(lines[end].text):
                end += 1
            return first, end
    return None


def assigned_symbol(line):
    """Return the symbol a line assigns for Kconfig, or None."""
    assignment = kconfig_assignment(line.text)
    return assignment[0] if assignment else None


def plan_assignments(path, text, names):
    """Plan rootfs_config: every name assigned exactly once, by 'CONFIG_<name>=y'."""
    plan = Plan('rootfs_config', path, text)
    lines = split_lines(text)
    eol = file_eol(lines)
    missing = []
    for name in names:
        exact = 'CONFIG_%s=y' % name
        found = [i for i, line in enumerate(lines) if assigned_symbol(line) == name]
        if not found:
            missing.append(name)
            continue
        # Kconfig applies every assignment, so the last one is what was in force.
        (plan.already if lines[found[-1]].text == exact else plan.done).append(name)
        keep = next((i for i in found if lines[i].text == exact), found[0])
        if lines[keep].text != exact:
            plan.fixes.append((name, 'line %d reads %r' % (lines[keep].number, lines[keep].text),
                               'made it %r in place' % exact))
            lines[keep].text = exact
        for i in found:
            if i != keep:
                plan.remove(lines, i, name, 'assigns it again')
        lines = [line for line in lines if line is not None]
    for name in missing:
        exact = 'CONFIG_%s=y' % name
        block = user_packages_block(lines)
        if block is None:
            index, where = len(lines), 'at the end (there is no user packages block)'
        else:
            first, end = block
            index = next((i for i in range(first, end) if assigned_symbol(lines[i]) > name),
                         end)
            where = 'in the user packages block'
        plan.fixes.append((name, 'not assigned', 'added %r %s' % (exact, where)))
        plan.done.append(name)
        insert_line(lines, index, exact, eol)
    plan.new_text = join_lines(lines)
    return plan


# ---------------------------------------------------------------------------------------------
# The layer files and the layer's layer.conf

class FilePlan:
    """Placing one file of petalinux/meta-user in the project's meta-user layer."""

    def __init__(self, relative, path, ours, theirs):
        self.relative = relative  # its path in both layers, e.g. 'recipes-ros/fastrtps/...'
        self.path = path          # where it goes in the project
        self.ours = ours          # its bytes in petalinux/meta-user
        self.theirs = theirs      # its bytes in the project, None when it is not there

    @property
    def state(self):
        """Return 'missing', 'same' or 'differs'."""
        if self.theirs is None:
            return 'missing'
        return 'same' if self.theirs == self.ours else 'differs'

    @property
    def problem(self):
        """Return what --check says about the file, None when it is in place."""
        if self.state == 'missing':
            return 'missing'
        if self.state == 'differs':
            return 'differs from petalinux/meta-user/%s' % self.relative
        return None


class LayerPlan:
    """Placing all of petalinux/meta-user: one FilePlan a file, and warnings about the rest."""

    def __init__(self, files):
        self.files = files
        self.warnings = []

    def count(self, state):
        """Return how many files are in a state."""
        return sum(1 for plan in self.files if plan.state == state)

    @property
    def differing(self):
        """Return the FilePlans of the files that are there with other content."""
        return [plan for plan in self.files if plan.state == 'differs']


def layer_files():
    """Return the files of petalinux/meta-user, as sorted paths relative to it."""
    found = []
    for directory, subdirectories, names in os.walk(LAYER_SOURCE):
        subdirectories[:] = sorted(name for name in subdirectories if not name.startswith('.'))
        found += [os.path.relpath(os.path.join(directory, name), LAYER_SOURCE)
                  for name in sorted(names) if not name.startswith('.')]
    if not found:
        raise ToolError('no layer files to place: %s is missing or empty' % LAYER_SOURCE)
    return found


def recipe_name(filename):
    """Return (name, extension) of a recipe or bbappend file name (bitbake's PN), else None."""
    stem, extension = os.path.splitext(filename)
    if extension not in ('.bb', '.bbappend'):
        return None
    return stem.split('_')[0], extension


def appends_to(bbappend, recipe):
    """Return whether bitbake applies a bbappend to a recipe, by their file names."""
    name = os.path.basename(bbappend)[:-len('.bbappend')] + '.bb'
    if '%' in name:  # bitbake's wildcard: the rest of the version
        return name.startswith(recipe[:name.index('%')])
    return name == recipe


def other_versions(project, relative):
    """Return warnings about other versions, in the project, of a recipe or bbappend placed."""
    name = os.path.basename(relative)
    ours = recipe_name(name)
    directory = os.path.join(project, META_USER, os.path.dirname(relative))
    try:
        names = sorted(os.listdir(directory)) if ours else []
    except OSError:
        return []
    warnings = []
    for other in names:
        if other == name or recipe_name(other) != ours:
            continue
        where = os.path.join(META_USER, os.path.dirname(relative), other)
        if ours[1] == '.bb':
            warnings.append('%s: another version of %s, which bitbake reads too: it builds the '
                            'highest version unless PREFERRED_VERSION_%s says otherwise; remove '
                            'it if it is an old copy' % (where, ours[0], ours[0]))
        else:
            warnings.append('%s: another bbappend of %s, which bitbake applies too wherever its '
                            'name matches the recipe; remove it if it is an old copy'
                            % (where, ours[0]))
    return warnings


def dangling_appends(project, relatives):
    """Return warnings for bbappends placed that no recipe of the project's Yocto layers takes."""
    layers = os.path.join(project, YOCTO_LAYERS)
    if not relatives or not os.path.isdir(layers):
        return []  # PetaLinux has not set up its layers yet: nothing to compare with
    names = {recipe_name(os.path.basename(relative))[0] for relative in relatives}
    recipes = {name: set() for name in names}
    for directory, subdirectories, files in os.walk(layers):
        subdirectories[:] = [name for name in subdirectories if not name.startswith('.')]
        for file in files:
            found = recipe_name(file)
            if found and found[1] == '.bb' and found[0] in recipes:
                recipes[found[0]].add(file)
    warnings = []
    for relative in relatives:
        name = recipe_name(os.path.basename(relative))[0]
        if not any(appends_to(relative, recipe) for recipe in recipes[name]):
            warnings.append(
                '%s: no recipe in %s takes it (%s recipes there: %s): bitbake will only warn '
                '("No recipes in default available for: ...", as PetaLinux sets '
                'BB_DANGLINGAPPENDS_WARNONLY) and build %s without it'
                % (os.path.join(META_USER, relative), YOCTO_LAYERS, name,
                   ', '.join(sorted(recipes[name])) or 'none', name))
    return warnings


def plan_layer(project):
    """Plan placing petalinux/meta-user's files in the project's meta-user layer."""
    files = []
    for relative in layer_files():
        source = os.path.join(LAYER_SOURCE, relative)
        ours = read_bytes(source, 'layer file')
        if ours is None:
            raise ToolError('layer file not found: %s' % source)
        path = os.path.join(project, META_USER, relative)
        files.append(FilePlan(relative, path, ours, read_bytes(path, 'meta-user file')))
    plan = LayerPlan(files)
    for file in files:
        plan.warnings += other_versions(project, file.relative)
    plan.warnings += dangling_appends(project, [file.relative for file in files
                                                if file.relative.endswith('.bbappend')])
    return plan


# bitbake's assignment line (lib/bb/parse/parse_py/ConfHandler.py): 'VAR[flag] op "value"'.
CONF_ASSIGNMENT = re.compile(
    r'(?:export\s+)?(?P<var>[a-zA-Z0-9\-_+.${}/~:]+?)(?P<flag>\[[a-zA-Z0-9\-_+.]+\])?\s*'
    r'(?P<op>:=|\?\?=|\?=|\+=|=\+|=\.|\.=|=)\s*(?P<quote>[\'"])(?P<value>.*)(?P=quote)\Z')


def conf_lines(text):
    """Return the statements of a bitbake .conf file: continued lines joined, no comments."""
    statements = []
    pending = None
    for line in re.split(r'\r\n|\r|\n', text):
        line = line.rstrip()
        if pending is not None:
            line = pending[:-1] + line
            pending = None
        if line.endswith('\\'):
            pending = line
            continue
        if line and not line.startswith('#'):
            statements.append(line)
    if pending is not None:
        statements.append(pending[:-1])
    return statements


def conf_words(text, variable):
    """
    Return the words this file leaves in a space-separated variable (BBFILES, BBMASK).

    What earlier files gave it counts as one word matching nothing: '?=' does nothing (it is
    set by then), '.=' glues onto that word, '=' replaces it; ':append', ':prepend' and
    ':remove' apply last, as bitbake applies them.
    """
    value = '\0'
    appended, prepended, removed = '', '', []
    for statement in conf_lines(text):
        match = CONF_ASSIGNMENT.match(statement)
        if not match or match.group('flag'):
            continue
        name, op, new = match.group('var'), match.group('op'), match.group('value')
        if name == variable:
            if op in ('=', ':='):
                value = new
            elif op == '+=':
                value = value + ' ' + new
            elif op == '=+':
                value = new + ' ' + value
            elif op == '.=':
                value = value + new
            elif op == '=.':
                value = new + value
        elif name == variable + ':append':
            appended += new
        elif name == variable + ':prepend':
            prepended = new + prepended
        elif name == variable + ':remove':
            removed += new.split()
    return [word for word in (prepended + value + appended).split() if word not in removed]


def glob_matches(pattern, path):
    """Return whether glob.glob(pattern) lists path: '*', '?', '[...]' within one path part."""
    patterns, parts = pattern.split('/'), path.split('/')
    return len(patterns) == len(parts) and all(
        fnmatch.fnmatchcase(part, wanted) and not (part.startswith('.') and wanted[:1] != '.')
        for part, wanted in zip(parts, patterns))


def not_picked_up(text, layer_dir, recipes):
    """Return the recipes (paths relative to the layer) that a layer.conf's BBFILES misses."""
    patterns = [word.replace('${LAYERDIR}', layer_dir) for word in conf_words(text, 'BBFILES')]
    return [relative for relative in recipes
            if not any(glob_matches(pattern, os.path.join(layer_dir, relative))
                       for pattern in patterns)]


def plan_layer_conf(path, text, layer_dir, recipes):
    """Plan layer.conf: its BBFILES picks up every recipe and bbappend placed."""
    plan = Plan('layer.conf', path, text)
    missing = not_picked_up(text, layer_dir, recipes)
    if missing:
        lines = split_lines(text)
        insert_line(lines, len(lines), BBFILES_LINE, file_eol(lines))
        plan.new_text = join_lines(lines)
        names = ', '.join(os.path.basename(relative) for relative in missing)
        if not_picked_up(plan.new_text, layer_dir, recipes):
            raise ToolError('%s: its BBFILES leaves out %s even with %r added (a BBFILES:remove '
                            'or an assignment that empties it?): edit it by hand'
                            % (path, names, BBFILES_LINE))
        plan.fixes.append(('BBFILES', 'does not pick up %s' % names,
                           'appended %r' % BBFILES_LINE))
        plan.done.append('BBFILES')
    else:
        plan.already.append('BBFILES')
    for mask in conf_words(text, 'BBMASK'):
        try:
            hidden = [relative for relative in recipes
                      if re.search(mask, os.path.join(layer_dir, relative))]
        except re.error:
            continue
        if hidden:
            plan.warnings.append('BBMASK %r hides %s from bitbake'
                                 % (mask, ', '.join(os.path.basename(h) for h in hidden)))
    return plan


# ---------------------------------------------------------------------------------------------
# The command line

def summary(plan, replace=False):
    """Return the one-line account of a plan, e.g. 'rootfs_config: enabled 6, already 2'."""
    if isinstance(plan, LayerPlan):
        text = 'meta-user: placed %d file(s), ' % plan.count('missing')
        if replace or not plan.differing:
            return text + 'replaced %d, already %d' % (plan.count('differs'), plan.count('same'))
        return text + 'already %d, %d differ(s) (replaced only with --replace)' % (
            plan.count('same'), plan.count('differs'))
    if plan.label == 'layer.conf':
        if plan.done:
            return 'layer.conf: BBFILES line appended'
        return 'layer.conf: BBFILES already picks up the recipes'
    verb = 'declared' if plan.label == 'user-rootfsconfig' else 'enabled'
    text = '%s: %s %d, already %d' % (plan.label, verb, len(plan.done), len(plan.already))
    if plan.removed:
        text += ', removed %d repeated line(s)' % plan.removed
    return text


def printable(text):
    """Return text safe to print whatever bytes the files held."""
    return text.encode('utf-8', 'surrogateescape').decode('utf-8', 'replace')


def unified_diff(old_text, new_text, name):
    """Return the unified diff of two texts of the file name (relative to the project)."""
    old, new = ([line.text + line.eol for line in split_lines(text)]
                for text in (old_text, new_text))
    out = []
    for line in difflib.unified_diff(old, new, 'a/' + name, 'b/' + name):
        out.append(line if line.endswith('\n') else line + '\n\\ No newline at end of file\n')
    return ''.join(out)


def diff(plan, project):
    """Return the unified diff of a plan, with paths relative to the project."""
    return unified_diff(plan.old_text, plan.new_text, os.path.relpath(plan.path, project))


def layer_diff(layer, project, replace):
    """Return what placing the layer files changes: a line per new file, a diff per other."""
    out = []
    for plan in layer.files:
        name = os.path.relpath(plan.path, project)
        if plan.state == 'missing':
            out.append('new file %s (petalinux/meta-user/%s, %d bytes)\n'
                       % (name, plan.relative, len(plan.ours)))
        elif plan.state == 'differs':
            out.append('%s %s with petalinux/meta-user/%s:\n'
                       % ('replacing' if replace else 'not replaced without --replace:', name,
                          plan.relative))
            out.append(unified_diff(*(data.decode('utf-8', 'surrogateescape')
                                      for data in (plan.theirs, plan.ours)), name))
    return ''.join(out)


def differing_error(layer, project):
    """Return the ToolError for layer files that differ and may not be replaced."""
    return ToolError(
        '%s differ%s from petalinux/meta-user/ (an older copy, or an edit of yours); see the '
        'difference with --dry-run, replace with --replace'
        % (', '.join(os.path.relpath(plan.path, project) for plan in layer.differing),
           's' if len(layer.differing) == 1 else ''))


def parse_args(argv):
    """Parse the command line."""
    parser = argparse.ArgumentParser(
        prog='enable_ros.py',
        description='Declare and enable the rootfs packages py_vision needs (ROS 2, OpenCV, '
                    'numpy, PyYAML, the TensorFlow Lite runtime, xauth, vision-msgs) in a '
                    'PetaLinux 2023.2 project (user-rootfsconfig and rootfs_config), and place '
                    "petalinux/meta-user's recipes in the project's meta-user layer.",
        epilog='Exit status: 0 done (--check: nothing missing), 1 --check: something is '
               'missing or differs, 2 error (a layer file that differs without --replace '
               'is one).')
    parser.add_argument('project', metavar='PROJECT_DIR', help='the PetaLinux project')
    parser.add_argument('--board', choices=sorted(BOARDS),
                        help='the board (default: read from project-spec/configs/config)')
    mode = parser.add_mutually_exclusive_group()
    mode.add_argument('--check', action='store_true',
                      help='write nothing; exit 0 when nothing is missing, 1 listing what is')
    mode.add_argument('--dry-run', action='store_true',
                      help='print the changes as a diff and write nothing')
    parser.add_argument('--replace', action='store_true',
                        help="replace a file of the project's meta-user layer that differs from "
                             'the one in petalinux/meta-user (without it the tool stops and '
                             'writes nothing)')
    args = parser.parse_args(argv)
    if args.replace and args.check:
        parser.error('argument --replace: not allowed with argument --check')
    return args


def run(args, out, err):
    """Do what the command line asks; return the exit status."""
    project = args.project
    if not os.path.isdir(project):
        raise ToolError('project directory not found: %s' % project)
    if not os.path.isdir(os.path.join(project, 'project-spec')):
        raise ToolError('not a PetaLinux project (no project-spec/ directory): %s' % project)
    if args.board:
        board, reason = args.board, 'given with --board'
        try:
            detected, how = detect_board(project)
        except ToolError:
            detected = board
        if detected != board:
            err.write('warning: the project looks like a %s board (%s); using --board %s\n'
                      % (detected, how, board))
    else:
        board, reason = detect_board(project)
        reason = 'from ' + reason
    declare, enable = load_fragments(board)
    declarations_path = os.path.join(project, USER_ROOTFSCONFIG)
    assignments_path = os.path.join(project, ROOTFS_CONFIG)
    layer_conf_path = os.path.join(project, LAYER_CONF)
    layer = plan_layer(project)
    declarations = plan_declarations(
        declarations_path, read_text(declarations_path, 'user-rootfsconfig'), declare)
    assignments = plan_assignments(
        assignments_path, read_text(assignments_path, 'rootfs_config'), enable)
    conf = plan_layer_conf(
        layer_conf_path, read_text(layer_conf_path, "the meta-user layer's layer.conf"),
        os.path.abspath(os.path.join(project, META_USER)),
        [plan.relative for plan in layer.files if recipe_name(os.path.basename(plan.relative))])
    plans = [declarations, assignments, conf]  # the text files' plans; the layer's is apart
    out.write('board: %s (%s), %s\n' % (board, BOARDS[board][0], reason))
    for plan in plans:
        for warning in plan.warnings:
            err.write('warning: %s: %s\n' % (os.path.relpath(plan.path, project),
                                             printable(warning)))
    for warning in layer.warnings:
        err.write('warning: %s\n' % printable(warning))
    if args.check:
        problems = ['%s: %s: %s' % (plan.label, name, printable(problem))
                    for plan in plans for name, problem, _ in plan.fixes]
        problems += ['meta-user: %s: %s' % (plan.relative, plan.problem)
                     for plan in layer.files if plan.problem]
        if not problems:
            out.write('fully enabled: %d packages declared, %d enabled, %d layer files in '
                      'place\n' % (len(declare), len(enable), len(layer.files)))
            return 0
        out.write('not fully enabled, %d problem(s):\n' % len(problems))
        out.write(''.join('  %s\n' % problem for problem in problems))
        out.write('run without --check to fix them%s\n'
                  % (' (with --replace for the files that differ)' if layer.differing else ''))
        return 1
    if args.dry_run:
        for plan in plans:
            out.write(printable(diff(plan, project)))
        out.write(printable(layer_diff(layer, project, args.replace)))
    else:
        if layer.differing and not args.replace:
            raise ToolError('nothing written: %s' % differing_error(layer, project))
        # The layer's files before the layer.conf line that makes bitbake read them.
        writes = [(plan.path, plan.new_text) for plan in (declarations, assignments)
                  if plan.changed]
        writes += [(plan.path, plan.ours) for plan in layer.files if plan.state != 'same']
        writes += [(conf.path, conf.new_text)] if conf.changed else []
        for path, content in writes:
            try:
                write_atomically(path, content)
            except OSError as error:
                raise ToolError('cannot write %s: %s' % (path, error.strerror or error))
    for plan in (declarations, assignments, layer, conf):
        out.write(summary(plan, args.replace) + '\n')
        if plan is layer:
            for file in layer.files:
                if file.problem:
                    out.write('  %s: %s: %s\n' % (file.relative, file.problem,
                                                  'copied' if file.state == 'missing'
                                                  else 'replaced' if args.replace
                                                  else 'needs --replace'))
            continue
        for name, problem, fix in plan.fixes:
            out.write(printable('  %s: %s: %s\n' % (name, problem, fix)))
    changed = any(plan.changed for plan in plans) or layer.count('same') < len(layer.files)
    if args.dry_run:
        if layer.differing and not args.replace:
            out.write('a run without --replace would stop and write nothing: %s\n'
                      % differing_error(layer, project))
        out.write('dry run: nothing written\n')
    elif not changed:
        out.write('nothing to change: the project is already fully enabled\n')
    out.write(NEXT_STEPS + '\n')
    return 0


def main(argv=None):
    """Run the tool; errors become one 'error:' line and exit status 2."""
    args = parse_args(argv)
    try:
        return run(args, sys.stdout, sys.stderr)
    except ToolError as error:
        sys.stderr.write('error: %s\n' % printable(str(error)))
        return 2
    except KeyboardInterrupt:
        sys.stderr.write('interrupted: nothing half-written\n')
        return 2


if __name__ == '__main__':
    sys.exit(main())
