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
The package as a ROS user or the build farm tests it: colcon build, colcon test, test-result.

A copy of the package goes into a new workspace's src/; colcon builds it and runs a few fast
tests of it (a linter and a node test), which must find the installed package from the
environment colcon test gives them, with nothing of this run's install in that environment.
"""

import os
from pathlib import Path
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET

import ros_harness

PACKAGE_DIR = Path(__file__).resolve().parents[2]
# The copyright linter's tests, a test that starts a node and reads its parameters through a
# peer, and one that needs the viewer's page files installed beside its modules: these must be
# among the tests that ran.
SELECTED = {'test_copyright', 'test_a_node_runs_with_exactly_the_values_of_its_params_file',
            'test_page_is_self_contained_with_the_video_and_stats_elements'}
SELECTION = ('test_copyright or (test_a_node_runs_with_exactly and cv_bridge_test) or '
             'test_page_is_self_contained')
STEP_TIMEOUT_S = 300


def colcon():
    """Return the colcon beside this Python (a venv's), else the one on PATH."""
    beside = Path(sys.executable).parent / 'colcon'
    return str(beside) if beside.is_file() else shutil.which('colcon') or 'colcon'


def workspace_env():
    """
    Return os.environ without what points at the py_vision this run tests or chooses its tests.

    PY_VISION_LINTERS=off and the like (conftest.py) would leave selected tests out.
    """
    env = dict(os.environ)
    for name in ('PY_VISION_INSTALL', 'PYTEST_ADDOPTS', 'PYTEST_CURRENT_TEST', 'COLCON',
                 'PY_VISION_LINTERS', 'PY_VISION_BROWSER', 'PY_VISION_VIVID'):
        env.pop(name, None)
    own = {str(ros_harness.PREFIX), str(ros_harness.SITE_PACKAGES)}
    for name in ('AMENT_PREFIX_PATH', 'PYTHONPATH', 'COLCON_PREFIX_PATH'):
        kept = [p for p in env.get(name, '').split(os.pathsep)
                if p and str(Path(p).resolve()) not in own]
        if kept:
            env[name] = os.pathsep.join(kept)
        else:
            env.pop(name, None)
    return env


def run(args, cwd):
    """Run a colcon step in the workspace; fail with the tail of its output if it fails."""
    done = subprocess.run(args, cwd=cwd, env=workspace_env(), stdout=subprocess.PIPE,
                          stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                          timeout=STEP_TIMEOUT_S)
    output = done.stdout.decode(errors='replace')
    assert done.returncode == 0, '%s exited with %d:\n%s' % (
        ' '.join(args[1:]), done.returncode, '\n'.join(output.splitlines()[-60:]))
    return output


def test_colcon_build_test_and_test_result_pass_in_a_plain_workspace(tmp_path):
    source = tmp_path / 'src' / 'py_vision'
    shutil.copytree(PACKAGE_DIR, source, ignore=shutil.ignore_patterns(
        '__pycache__', '.pytest_cache', '.hypothesis'))
    run([colcon(), 'build'], tmp_path)
    # The workspace holds only py_vision: `colcon test` is `colcon test --packages-select
    # py_vision` there, without needing colcon-package-selection.
    run([colcon(), 'test', '--pytest-args', '-k', SELECTION], tmp_path)
    summary = run([colcon(), 'test-result', '--verbose'], tmp_path)
    assert '0 errors, 0 failures' in summary, summary

    # The selected tests ran (not skipped) against the workspace's own install.
    results = ET.parse(tmp_path / 'build' / 'py_vision' / 'pytest.xml').getroot()
    cases = {case.get('name').split('[')[0]: case for case in results.iter('testcase')}
    assert SELECTED <= set(cases), 'ran %s, not all of %s' % (sorted(cases), sorted(SELECTED))
    for name, case in cases.items():
        assert len(case) == 0 or all(child.tag in ('system-out', 'system-err')
                                     for child in case), '%s did not pass' % name
