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
Declare and enable the rootfs packages py_vision needs in a PetaLinux 2023.2 project.

Usage: python3 petalinux/enable_ros.py PROJECT_DIR [--board B] [--check | --dry-run]

The package lists come from petalinux/boards/<board>/user-rootfsconfig (declarations) and
petalinux/boards/<board>/rootfs_config (enabled packages): the tutorial's ROS 2 packages, the
Python modules py_vision imports (OpenCV, numpy, PyYAML), xauth for ssh -X windows and
vision-msgs (the faces step's detections). The tool edits two project files, keeping every
byte it has no reason to touch:

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

Writes are atomic (temporary file in the same directory, fsync, rename), keep the file mode
and go through symlinks to their target. Running the tool again changes nothing.
Exit status: 0 done (or --check: fully enabled), 1 --check: something is missing,
2 bad usage, missing project or file, unknown board, unreadable or unwritable file.
"""

import argparse
import difflib
import os
import re
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
BOARDS_DIR = os.path.join(HERE, 'boards')

USER_ROOTFSCONFIG = os.path.join('project-spec', 'meta-user', 'conf', 'user-rootfsconfig')
ROOTFS_CONFIG = os.path.join('project-spec', 'configs', 'rootfs_config')
PROJECT_CONFIG = os.path.join('project-spec', 'configs', 'config')

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


def write_atomically(path, text):
    """Replace a file's content so that a crash leaves either the old or the new file."""
    target = os.path.realpath(path)  # replace a symlink's target, not the link
    directory = os.path.dirname(target)
    mode = os.stat(target).st_mode & 0o7777
    fd, temporary = tempfile.mkstemp(prefix='.%s.' % os.path.basename(target),
                                     suffix='.enable_ros.tmp', dir=directory)
    try:
        with os.fdopen(fd, 'wb') as stream:
            stream.write(text.encode('utf-8', 'surrogateescape'))
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
# The command line

def summary(plan):
    """Return the one-line account of a plan, e.g. 'rootfs_config: enabled 6, already 2'."""
    verb = 'declared' if plan.label == 'user-rootfsconfig' else 'enabled'
    text = '%s: %s %d, already %d' % (plan.label, verb, len(plan.done), len(plan.already))
    if plan.removed:
        text += ', removed %d repeated line(s)' % plan.removed
    return text


def printable(text):
    """Return text safe to print whatever bytes the files held."""
    return text.encode('utf-8', 'surrogateescape').decode('utf-8', 'replace')


def diff(plan, project):
    """Return the unified diff of a plan, with paths relative to the project."""
    name = os.path.relpath(plan.path, project)
    old, new = ([line.text + line.eol for line in split_lines(text)]
                for text in (plan.old_text, plan.new_text))
    out = []
    for line in difflib.unified_diff(old, new, 'a/' + name, 'b/' + name):
        out.append(line if line.endswith('\n') else line + '\n\\ No newline at end of file\n')
    return ''.join(out)


def parse_args(argv):
    """Parse the command line."""
    parser = argparse.ArgumentParser(
        prog='enable_ros.py',
        description='Declare and enable the rootfs packages py_vision needs (ROS 2, OpenCV, '
                    'numpy, PyYAML, xauth, vision-msgs) in a PetaLinux 2023.2 project '
                    '(user-rootfsconfig and rootfs_config).',
        epilog='Exit status: 0 done (--check: fully enabled), 1 --check: something is '
               'missing, 2 error.')
    parser.add_argument('project', metavar='PROJECT_DIR', help='the PetaLinux project')
    parser.add_argument('--board', choices=sorted(BOARDS),
                        help='the board (default: read from project-spec/configs/config)')
    mode = parser.add_mutually_exclusive_group()
    mode.add_argument('--check', action='store_true',
                      help='write nothing; exit 0 when fully enabled, 1 listing what is not')
    mode.add_argument('--dry-run', action='store_true',
                      help='print the changes as a diff and write nothing')
    return parser.parse_args(argv)


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
    plans = [
        plan_declarations(declarations_path, read_text(declarations_path, 'user-rootfsconfig'),
                          declare),
        plan_assignments(assignments_path, read_text(assignments_path, 'rootfs_config'),
                         enable),
    ]
    out.write('board: %s (%s), %s\n' % (board, BOARDS[board][0], reason))
    for plan in plans:
        for warning in plan.warnings:
            err.write('warning: %s: %s\n' % (os.path.relpath(plan.path, project),
                                             printable(warning)))
    if args.check:
        problems = ['%s: %s: %s' % (plan.label, name, printable(problem))
                    for plan in plans for name, problem, _ in plan.fixes]
        if not problems:
            out.write('fully enabled: %d packages declared, %d enabled\n'
                      % (len(declare), len(enable)))
            return 0
        out.write('not fully enabled, %d problem(s):\n' % len(problems))
        out.write(''.join('  %s\n' % problem for problem in problems))
        out.write('run without --check to fix them\n')
        return 1
    if args.dry_run:
        for plan in plans:
            out.write(printable(diff(plan, project)))
    else:
        for plan in plans:
            if plan.changed:
                try:
                    write_atomically(plan.path, plan.new_text)
                except OSError as error:
                    raise ToolError('cannot write %s: %s'
                                    % (plan.path, error.strerror or error))
    for plan in plans:
        out.write(summary(plan) + '\n')
        for name, problem, fix in plan.fixes:
            out.write(printable('  %s: %s: %s\n' % (name, problem, fix)))
    if args.dry_run:
        out.write('dry run: nothing written\n')
    elif not any(plan.changed for plan in plans):
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
