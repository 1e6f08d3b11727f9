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
The board-version run is the image: petalinux/image_python.txt against all that must agree.

image_python.txt lists the Python modules py_vision imports at run time, with the versions an
image built with petalinux/ has. These tests fail where it and the rest disagree:
- the boards' fragments: the package that brings a module is declared and enabled on every
  board;
- petalinux/meta-user's recipes: a module one of them brings has that recipe's version;
- requirements-board.txt: its image section pins exactly the image's versions, its tools
  section none of these modules (nor those no board image has);
- py_vision's own imports: each is a module the image has, or one it lacks that py_vision
  imports only where it may be missing.
check_board_env.py, which checks the board-version run's environment itself, is tested here
on made-up environments; scripts/test.sh runs it on the real one.
"""

import ast
import importlib.util
from pathlib import Path
import re
import sys

import pytest

HERE = Path(__file__).resolve().parent
PETALINUX = HERE.parent
REPO = PETALINUX.parent
REQUIREMENTS = REPO / 'requirements-board.txt'
# What py_vision runs on a board: the package's modules and its launch files.
SOURCES = [REPO / 'py_vision' / 'py_vision', REPO / 'py_vision' / 'launch']
SECTIONS = ('image', 'tools')


def load(name, path):
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


check_board_env = load('check_board_env', PETALINUX / 'check_board_env.py')
enable_ros = load('enable_ros', PETALINUX / 'enable_ros.py')
ROWS = check_board_env.read_table()


def normalized(name):
    """Return a distribution name as pip compares them (PEP 503)."""
    return re.sub(r'[-_.]+', '-', name).lower()


# ---------------------------------------------------------------------------------------------
# The checks, each on its inputs, so that each can be shown to fail

def fragment_problems(rows, fragments):
    """Return rows whose package a board does not declare and enable ({board: (d, e)})."""
    return ['%s: %s is not %s on %s' % (row.name, row.package, what, board)
            for board, (declared, enabled) in sorted(fragments.items())
            for row in rows if not row.absent
            for what, names in (('declared', declared), ('enabled', enabled))
            if row.package not in names]


def recipe_problems(rows, recipe_names):
    """Return rows whose version is not that of petalinux/meta-user's recipe of their package."""
    versions = dict(name[:-len('.bb')].split('_', 1) for name in recipe_names)
    return ['%s: the image has %s %s (%s_%s.bb), the table says %s'
            % (row.name, row.package, versions[row.package], row.package,
               versions[row.package], row.version)
            for row in rows if row.package in versions and row.version != versions[row.package]]


def requirement_sections(text):
    """Return ({section: {normalized name: version}}, problems) of requirements-board.txt."""
    sections, problems, current = {}, [], None
    for number, line in enumerate(text.splitlines(), start=1):
        heading = re.fullmatch(r'# == (\w+): .* ==', line)
        if heading:
            current = heading.group(1)
            if current not in SECTIONS or current in sections:
                problems.append('line %d: section %r (expected each of %s once)'
                                % (number, current, ', '.join(SECTIONS)))
            sections.setdefault(current, {})
            continue
        requirement = line.split('#')[0].strip()
        if not requirement:
            continue
        pin = re.fullmatch(r'([A-Za-z0-9][A-Za-z0-9._-]*)==([0-9][0-9A-Za-z.]*)', requirement)
        if not pin:
            problems.append('line %d: %r is not a NAME==VERSION pin' % (number, requirement))
        elif current is None:
            problems.append('line %d: %r comes before any section' % (number, requirement))
        else:
            sections[current][normalized(pin.group(1))] = pin.group(2)
    problems += ['no %s section' % name for name in SECTIONS if name not in sections]
    return sections, problems


def requirement_problems(rows, text):
    """Return where requirements-board.txt and the image disagree."""
    sections, problems = requirement_sections(text)
    image, tools = sections.get('image', {}), sections.get('tools', {})
    from_pip = {normalized(row.pip): row for row in rows if row.pip not in ('humble', '-')}
    for name, version in sorted(image.items()):
        row = from_pip.get(name)
        if row is None:
            problems.append('image section: %s==%s is no module of the image table'
                            % (name, version))
        elif row.absent:
            problems.append('image section: %s==%s, but no board image has %s'
                            % (name, version, row.name))
        elif not check_board_env.same_release(version, row.version):
            problems.append('image section: %s==%s, the image has %s %s'
                            % (name, version, row.package, row.version))
    for name, row in sorted(from_pip.items()):
        if not row.absent and name not in image:
            problems.append('image section: %s (%s %s) is not pinned'
                            % (name, row.package, row.version))
        if name in tools:
            problems.append('tools section: %s==%s is %s, which %s' % (
                name, tools[name], row.name,
                'no board image has' if row.absent else 'belongs in the image section'))
    return problems


def imported_modules(paths):
    """Return {top-level module: [(file, line, optional)]} of what the sources import."""
    found = {}
    for directory, path in sorted((d, p) for d in paths for p in d.rglob('*.py')):
        tree = ast.parse(path.read_text(), str(path))
        guarded = set()
        for node in ast.walk(tree):
            if isinstance(node, ast.Try) and any(
                    handler.type is not None and any(
                        isinstance(name, ast.Name)
                        and name.id in ('ImportError', 'ModuleNotFoundError')
                        for name in ast.walk(handler.type))
                    for handler in node.handlers):
                guarded.update(id(inner) for statement in node.body
                               for inner in ast.walk(statement))
        for node in ast.walk(tree):
            names = []
            if isinstance(node, ast.Import):
                names = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom) and node.level == 0:
                names = [node.module]
            elif (isinstance(node, ast.Call) and node.args
                  and isinstance(node.args[0], ast.Constant)
                  and isinstance(node.args[0].value, str)
                  and getattr(node.func, 'id', getattr(node.func, 'attr', None))
                  in ('import_module', '_import')):
                # importlib.import_module or py_vision.models.runtime's _import, which both
                # return None for a module that is missing: optional.
                names = [node.args[0].value]
                guarded.add(id(node))
            for name in names:
                found.setdefault(name.split('.')[0], []).append(
                    (path.relative_to(directory.parent), node.lineno, id(node) in guarded))
    return found


def import_problems(rows, imports):
    """Return py_vision's imports that an image built with petalinux/ cannot satisfy."""
    table = {row.module: row for row in rows}
    problems = []
    for module, places in sorted(imports.items()):
        if module in sys.stdlib_module_names or module == 'py_vision':
            continue
        row = table.get(module)
        where = ', '.join('%s:%d' % place[:2] for place in places)
        if row is None:
            problems.append("%s (%s) is in no image: add its package to the boards' fragments "
                            'and a row to image_python.txt' % (module, where))
        elif row.absent:
            required = ['%s:%d' % place[:2] for place in places if not place[2]]
            if required:
                problems.append('%s is imported unguarded (%s), but no board image has it'
                                % (module, ', '.join(required)))
    return problems


# ---------------------------------------------------------------------------------------------
# The real files

def test_the_table_lists_the_image_modules_and_the_absent_ones():
    present = [row.module for row in ROWS if not row.absent]
    absent = [row.module for row in ROWS if row.absent]
    assert {'cv2', 'numpy', 'yaml', 'tflite_runtime', 'vision_msgs', 'rclpy'} <= set(present)
    assert {'ai_edge_litert', 'onnxruntime'} <= set(absent)
    assert len({row.module for row in ROWS}) == len(ROWS)


def test_every_board_declares_and_enables_the_packages_of_the_image_modules():
    fragments = {board: enable_ros.load_fragments(board) for board in enable_ros.BOARDS}
    assert fragment_problems(ROWS, fragments) == []
    fragments['u96v2'] = ([name for name in fragments['u96v2'][0]
                           if name != 'python3-tflite-runtime'], fragments['u96v2'][1])
    assert fragment_problems(ROWS, fragments) == [
        'tflite_runtime: python3-tflite-runtime is not declared on u96v2']


def test_a_module_of_a_petalinux_recipe_has_that_recipes_version():
    names = [path.name for path in (PETALINUX / 'meta-user').rglob('*.bb')]
    assert 'python3-tflite-runtime_2.14.0.bb' in names
    assert recipe_problems(ROWS, names) == []
    assert recipe_problems(ROWS, ['python3-tflite-runtime_2.15.0.bb']) == [
        'tflite_runtime: the image has python3-tflite-runtime 2.15.0 '
        '(python3-tflite-runtime_2.15.0.bb), the table says 2.14.0']


def test_requirements_board_pins_what_the_image_has_and_nothing_it_lacks():
    text = REQUIREMENTS.read_text()
    assert requirement_problems(ROWS, text) == []
    image, _ = requirement_sections(text)
    assert image['image'] == {'opencv-python-headless': '4.6.0.66', 'numpy': '1.23.3',
                              'pyyaml': '6.0', 'tflite-runtime': '2.14.0'}


@pytest.mark.parametrize('change, problem', [
    (('PyYAML==6.0\n', 'PyYAML==6.0.4\n'), 'image section: pyyaml==6.0.4, the image has '
                                           'python3-pyyaml 6.0'),
    (('numpy==1.23.3\n', ''), 'image section: numpy (python3-numpy 1.23.3) is not pinned'),
    (('tflite-runtime==2.14.0\n', 'tflite-runtime==2.14.0\nonnxruntime==1.16.3\n'),
     'image section: onnxruntime==1.16.3, but no board image has onnxruntime'),
    (('tflite-runtime==2.14.0\n', 'tflite-runtime==2.14.0\nscikit-learn==1.3.2\n'),
     'image section: scikit-learn==1.3.2 is no module of the image table'),
    (('pytest==', 'ai_edge_litert==1.0.1\npytest=='),
     'tools section: ai-edge-litert==1.0.1 is ai_edge_litert, which no board image has'),
    (('pytest==', 'numpy==1.23.3\npytest=='),
     'tools section: numpy==1.23.3 is numpy, which belongs in the image section'),
    (('# == tools:', '# == extra:'), "section 'extra' (expected each of image, tools once)"),
])
def test_requirements_that_differ_from_the_image_are_found(change, problem):
    text = REQUIREMENTS.read_text()
    assert change[0] in text
    found = requirement_problems(ROWS, text.replace(change[0], change[1], 1))
    assert any(problem in line for line in found), found


def test_py_vision_imports_only_what_the_image_has():
    imports = imported_modules(SOURCES)
    # The scan sees the imports that matter: a required one, a guarded one, a dynamic one.
    assert any(not optional for _, _, optional in imports['numpy'])
    assert all(optional for _, _, optional in imports['foxglove_msgs'])
    assert all(optional for _, _, optional in imports['onnxruntime'])
    assert 'tflite_runtime' in imports and 'launch_ros' in imports
    assert import_problems(ROWS, imports) == []


def test_imports_the_image_cannot_satisfy_are_found(tmp_path):
    (tmp_path / 'steps.py').write_text(
        'import numpy\nimport onnxruntime\nfrom scipy import ndimage\n'
        'try:\n    import ai_edge_litert\nexcept ImportError:\n    ai_edge_litert = None\n')
    found = import_problems(ROWS, imported_modules([tmp_path]))
    assert len(found) == 2, found
    assert found[0].startswith('onnxruntime is imported unguarded')
    assert found[1].startswith('scipy (')


# ---------------------------------------------------------------------------------------------
# check_board_env.py on made-up environments

class Environment:
    """A made-up environment: the modules that import, and their versions."""

    def __init__(self, **changes):
        self.versions = {row.name: row.version for row in ROWS if not row.absent}
        self.versions.update(changes)

    def import_module(self, name):
        if self.versions.get(name) is None:
            raise ModuleNotFoundError("No module named '%s'" % name)

    def version_of(self, row):
        return self.versions[row.name]


def env_problems(python=(3, 10), **changes):
    environment = Environment(**changes)
    return check_board_env.problems(ROWS, environment.import_module, environment.version_of,
                                    python)


def test_the_environment_check_passes_the_image():
    assert env_problems() == []
    assert env_problems(cv2='4.6.0.66') == []


@pytest.mark.parametrize('changes, problem', [
    ({'yaml': '6.0.4'}, 'yaml is 6.0.4 here, the image has 6.0 (python3-pyyaml)'),
    ({'numpy': '1.23.30'}, 'numpy is 1.23.30 here, the image has 1.23.3'),
    ({'tflite_runtime': None}, 'tflite_runtime does not import'),
    ({'vision_msgs.msg': None}, 'vision_msgs.msg does not import'),
    ({'onnxruntime': '1.16.3'}, 'onnxruntime imports, but no board image has it'),
    ({'ai_edge_litert': '1.0.1'}, 'ai_edge_litert imports, but no board image has it'),
    ({'python': (3, 11)}, 'Python is 3.11, the image has 3.10'),
])
def test_the_environment_check_finds_what_differs_from_the_image(changes, problem):
    found = env_problems(**changes)
    assert len(found) == 1 and found[0].startswith(problem), found


@pytest.mark.parametrize('installed, image, same', [
    ('4.6.0.66', '4.6.0', True), ('6.0', '6.0', True), ('6.0.4', '6.0', False),
    ('1.23.30', '1.23.3', False), ('4.6.0.x', '4.6.0', False), ('2.14.0', '2.14.0', True),
])
def test_a_release_is_the_images_or_its_pypi_build(installed, image, same):
    assert check_board_env.same_release(installed, image) is same
