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
What PetaLinux 2023.2, Kconfig and bitbake read from the project's files, for the tests.

Written independently of enable_ros.py, from how the readers behave:
- PetaLinux (gen-machineconf) opens user-rootfsconfig in Python text mode, turns each line
  into a one-element list, and for every line whose text holds 'CONFIG_' (comments too)
  declares what lies between the first and the second underscore (or the closing quote).
- Kconfig reads rootfs_config line by line (LF ends a line, a CR before it is dropped):
  'CONFIG_<sym>=<value>' assigns the rest of the line, '#?CONFIG_<sym> is not set' assigns n,
  the last assignment of a symbol wins.
- After Kconfig, PetaLinux puts in the image every line that has no '#' and ends in '=y'.
- bitbake reads the meta-user layer's recipes from the files its conf/layer.conf's BBFILES
  patterns glob (Python's glob, after ${LAYERDIR} is put in), and applies a .bbappend to the
  .bb of the same file name, '%' in the append's name standing for any rest.
"""

import glob
import io


def text_mode_lines(data):
    """Return the lines Python's text mode yields for these bytes (universal newlines)."""
    stream = io.TextIOWrapper(io.BytesIO(data), encoding='utf-8', errors='surrogateescape')
    return [line.splitlines() for line in stream]


def declarations(data):
    """Return the package names PetaLinux declares from user-rootfsconfig bytes, in order."""
    names = []
    for line in text_mode_lines(data):
        as_text = str(line)
        if 'CONFIG_' in as_text:
            after_first_underscore = as_text.split('_')[1]
            names.append(after_first_underscore.split("'")[0])
    return names


def kconfig_lines(data):
    """Return the lines of rootfs_config bytes as Kconfig's reader sees them."""
    text = data.decode('utf-8', 'surrogateescape')
    lines = text.split('\n')
    if lines and lines[-1] == '':
        lines.pop()
    return [line[:-1] if line.endswith('\r') else line for line in lines]


def assignments(data):
    """Return {symbol: [values in file order]} for rootfs_config bytes ('n' for is not set)."""
    values = {}
    for line in kconfig_lines(data):
        if line.startswith('#'):
            if line[2:9] != 'CONFIG_':
                continue
            space = line.find(' ', 9)
            if space < 0 or not line[space + 1:].startswith('is not set'):
                continue
            values.setdefault(line[9:space], []).append('n')
        elif line.startswith('CONFIG_') and '=' in line:
            symbol, _, value = line[7:].partition('=')
            values.setdefault(symbol, []).append(value)
    return values


def image_packages(data):
    """Return the packages PetaLinux installs from rootfs_config bytes, in order."""
    packages = []
    for line in text_mode_lines(data):
        as_text = str(line)
        if '#' in as_text or not as_text.endswith("=y']"):
            continue
        packages.append(as_text.split('_')[1].split('=')[0])
    return packages


# ---------------------------------------------------------------------------------------------
# What bitbake reads from the meta-user layer (bitbake 2.2, PetaLinux 2023.2's)

def conf_statements(data):
    """
    Return the statements bitbake reads from .conf bytes, as ConfHandler.handle does.

    Text mode, one line at a time: a line whose right-stripped text ends in a backslash goes
    on with the next line (the backslash dropped, the next line right-stripped), blank lines
    and lines starting with '#' are skipped.
    """
    stream = io.TextIOWrapper(io.BytesIO(data), encoding='utf-8', errors='surrogateescape')
    statements = []
    while True:
        line = stream.readline()
        if not line:
            return statements
        if not line.strip():
            continue
        text = line.rstrip()
        while text.endswith('\\'):
            text = text[:-1] + stream.readline().rstrip()
        if not text.startswith('#'):
            statements.append(text)


def variable_words(data, variable, before='<earlier layers>'):
    """Return the words a .conf file leaves in a variable that earlier files set to `before`."""
    value, tail = before, []
    operators = [(':=', 'set'), ('??=', 'keep'), ('?=', 'keep'), ('+=', 'append'),
                 ('=+', 'prepend'), ('.=', 'glue'), ('=.', 'glue-front'), ('=', 'set')]
    for statement in conf_statements(data):
        left, quote, rest = statement.partition('"')
        if not quote or not rest.endswith('"'):
            continue
        new = rest[:-1]
        for operator, action in operators:
            if left.rstrip().endswith(operator):
                name = left.rstrip()[:-len(operator)].strip()
                break
        else:
            continue
        if name == variable:
            value = {'set': new, 'keep': value, 'append': value + ' ' + new,
                     'prepend': new + ' ' + value, 'glue': value + new,
                     'glue-front': new + value}[action]
        elif name.startswith(variable + ':'):
            tail.append((name[len(variable) + 1:], new))
    for override, new in tail:  # applied when the variable is read
        if override == 'append':
            value += new
        elif override == 'prepend':
            value = new + value
    removed = {word for override, new in tail if override == 'remove' for word in new.split()}
    return [word for word in value.split() if word not in removed]


def bbfiles(layer_conf, layerdir):
    """Return the files bitbake collects for the layer at layerdir: its BBFILES, globbed."""
    files = []
    for pattern in variable_words(layer_conf, 'BBFILES'):
        for path in sorted(glob.glob(pattern.replace('${LAYERDIR}', str(layerdir)))):
            if path not in files:
                files.append(path)
    return files


def appends_to(bbappend_name, recipe_name):
    """Return whether bitbake applies a .bbappend to a .bb (file names; '%': any rest)."""
    append = bbappend_name.replace('.bbappend', '.bb')
    if '%' in append:
        return append.startswith(recipe_name[:append.index('%')])
    return append == recipe_name
