#!/usr/bin/env bash
# Set everything up (scripts/setup.sh --test) and run the tests: the package's own where the
# package alone is, as a ROS user runs them (a copy of py_vision/ in a new colcon workspace,
# `colcon build`, `colcon test`, `colcon test-result`), then the repository's (tests/: its docs
# against the code and the lint of its tools; petalinux/test). If they pass, the package's
# tests that need no browser run again on the boards' software: Python 3.10, numpy 1.23.3,
# OpenCV 4.6.0 and their ROS 2 Humble (from ../shared/humble, set up by scripts/setup.sh
# --board in .venv-board), again with colcon in a plain workspace. Without a Python 3.10 or
# that Humble that second run is skipped, with the reason, on a developer's PC; in CI (CI=true)
# it is required, so that is a failure.
# Extra arguments go to pytest, in every run (e.g. -k bridge, -x).
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
bash "$root/scripts/setup.sh" --test
cd "$root"
in_ci=false
[ "${CI:-}" = true ] && in_ci=true

# The browser-viewer test drives Debian's Chromium, and the lint of the viewer page's script
# runs Debian's ESLint. Install each only when it is missing, only as root with apt, and never
# upgrade what is installed: --no-upgrade keeps installed packages as they are, and on a
# developer's PC apt is asked first (-s) whether the install would upgrade any other package
# (a newer dependency); if so nothing is installed and the test is skipped. CI's machine is the
# project's own: there the package is installed whatever it needs.
# Usage: install_tool PACKAGE 'WHAT NEEDS IT' [COMMAND...] (the commands that show it is there;
# without any, the PACKAGE words are Debian packages, each there when dpkg has it installed).
install_tool() {
  local package=$1 what=$2 log=/tmp/py_vision-apt.log plan upgrades command name missing=
  shift 2
  for command in "$@"; do
    command -v "$command" >/dev/null 2>&1 && return
  done
  if [ $# = 0 ]; then
    for name in $package; do
      dpkg-query -W -f='${Status}' "$name" 2>/dev/null | grep -q 'ok installed' \
        || missing="$missing $name"
    done
    [ -z "$missing" ] && return
    package=${missing# }
  fi
  if [ "$(id -u)" != 0 ] || ! command -v apt-get >/dev/null 2>&1; then
    echo "[test] $package is missing: $what will be skipped (in CI: fail)" \
      "(install Debian's $package)"
    return
  fi
  if [ "$in_ci" = true ]; then
    apt-get update -qq >$log 2>&1 || true
  elif ! plan=$(apt-get install -s --no-upgrade $package 2>$log); then
    echo "[test] $package is missing and apt cannot install it (see $log; apt-get update" \
      "may help): $what will be skipped"
    return
  elif upgrades=$(grep '^Inst [^ ]* \[' <<<"$plan"); then
    # 'Inst NAME [installed version] (new version ...)' is an upgrade.
    echo "[test] $package is missing, and installing it would upgrade $(wc -l <<<"$upgrades")" \
      "installed package(s) ($(head -3 <<<"$upgrades" | cut -d' ' -f2 | paste -sd,), ...):" \
      "they are left as they are and $what will be skipped;" \
      "to run it: apt-get install $package"
    return
  fi
  echo "[test] installing $package for $what"
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-upgrade $package >>$log 2>&1 \
    || echo "[test] could not install $package (see $log)"
}
[ -n "${CHROMIUM:-}" ] \
  || install_tool chromium 'the browser-viewer test' chromium chromium-browser
install_tool eslint "the lint of the viewer page's script" eslint

# The hand tests' photograph (py_vision/test/photos.py): OpenCV's documentation's handSrc.jpg,
# an open hand, from Debian's opencv-doc package, which is downloaded (not installed) and only
# that file taken out, into .venv/test-photos/. Where opencv-doc is installed it is used as it is.
# Without apt the real-hand tests are skipped, and fail in CI.
fetch_hand_photo() {
  local file=usr/share/doc/opencv-doc/opencv4/html/handSrc.jpg dir=$root/.venv/test-photos
  local log=/tmp/py_vision-apt.log tmp
  if [ -f "/$file" ]; then
    export PY_VISION_HAND_PHOTO=/$file
    return
  fi
  export PY_VISION_HAND_PHOTO=$dir/handSrc.jpg
  [ -s "$PY_VISION_HAND_PHOTO" ] && return
  if ! command -v apt-get >/dev/null 2>&1 || ! command -v dpkg-deb >/dev/null 2>&1; then
    echo "[test] no apt-get: the tests on a photograph of a hand will be skipped (in CI: fail)"
    return
  fi
  echo "[test] taking the hand photograph out of Debian's opencv-doc package"
  tmp=$(mktemp -d)
  if ! (cd "$tmp" && apt-get download opencv-doc >>$log 2>&1); then
    [ "$(id -u)" = 0 ] && apt-get update -qq >>$log 2>&1
    (cd "$tmp" && apt-get download opencv-doc >>$log 2>&1) || true
  fi
  mkdir -p "$dir"
  if ls "$tmp"/opencv-doc_*.deb >/dev/null 2>&1 \
      && dpkg-deb --fsys-tarfile "$tmp"/opencv-doc_*.deb | tar -x -O "./$file" \
        >"$PY_VISION_HAND_PHOTO.part" 2>>$log && [ -s "$PY_VISION_HAND_PHOTO.part" ]; then
    mv "$PY_VISION_HAND_PHOTO.part" "$PY_VISION_HAND_PHOTO"
  else
    rm -f "$PY_VISION_HAND_PHOTO.part"
    echo "[test] could not get opencv-doc (see $log): the tests on a photograph of a hand" \
      'will be skipped (in CI: fail)'
  fi
  rm -rf "$tmp"
}
fetch_hand_photo

# The emulated UVC cameras (py_vision/test/uvc_emulator) are a small C library the tests compile
# with the system C compiler. Install one from the distribution where `cc` is missing (as root,
# with apt); otherwise say so: those tests are then skipped, and in CI they fail.
install_compiler() {
  local log=/tmp/py_vision-apt.log
  if command -v cc >/dev/null 2>&1 || command -v gcc >/dev/null 2>&1; then
    return
  fi
  if [ "$(id -u)" != 0 ] || ! command -v apt-get >/dev/null 2>&1; then
    echo '[test] no C compiler (cc): the emulated-camera tests will be skipped (in CI: fail)' \
      '(install one: apt-get install gcc)'
    return
  fi
  echo '[test] installing a C compiler (gcc) for the emulated-camera tests'
  [ "$in_ci" = true ] && { apt-get update -qq >$log 2>&1 || true; }
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-upgrade gcc libc6-dev >>$log 2>&1 \
    || echo "[test] could not install gcc (see $log)"
}
install_compiler

# petalinux/test checks the image's recipes with the tools a build uses: the Fast DDS patches
# applied to Fast DDS' own files with GNU patch, and the shared-memory recovery compiled from
# them with g++ and Debian's Boost headers (test_fast_dds_patches.py); and bitbake 2.2 from
# ../shared/yocto on the recipes enable_ros.py places (test_bitbake.py), which needs the host
# tools its HOSTTOOLS check asks for (chrpath, diffstat, gawk and cpio are not in a minimal
# Debian), zstd to unpack the layers, and the en_US.UTF-8 locale, generated here where it is
# missing (as root, with Debian's locales). Without them those tests are skipped with the
# reason, and fail in CI.
install_tool 'g++ libboost-dev patch' 'the Fast DDS patch tests (petalinux/test)'
install_tool 'chrpath diffstat gawk cpio zstd' 'the bitbake tests (petalinux/test)'
setup_bitbake_locale() {
  local log=/tmp/py_vision-apt.log
  locale -a 2>/dev/null | grep -qiE '^en_US\.utf-?8$' && return
  if [ "$(id -u)" != 0 ]; then
    echo '[test] no en_US.UTF-8 locale: the bitbake tests will be skipped (in CI: fail)' \
      '(as root: enable en_US.UTF-8 in /etc/locale.gen, then locale-gen)'
    return
  fi
  install_tool locales 'the en_US.UTF-8 locale of the bitbake tests' locale-gen
  if ! command -v locale-gen >/dev/null 2>&1; then
    return
  fi
  echo '[test] generating the en_US.UTF-8 locale for the bitbake tests'
  touch /etc/locale.gen
  grep -q '^en_US.UTF-8 UTF-8' /etc/locale.gen \
    || sed -i 's/^# *en_US.UTF-8 UTF-8/en_US.UTF-8 UTF-8/' /etc/locale.gen
  grep -q '^en_US.UTF-8 UTF-8' /etc/locale.gen || echo 'en_US.UTF-8 UTF-8' >>/etc/locale.gen
  locale-gen >>$log 2>&1 \
    || echo "[test] locale-gen failed (see $log): the bitbake tests will be skipped (in CI: fail)"
}
setup_bitbake_locale

# The capture tests on the kernel's vivid driver (docs/vivid.md) boot a QEMU VM: QEMU, busybox,
# kmod and Debian's kernel, set up by scripts/vivid_vm.sh (one line where it cannot; those tests
# are then skipped, and fail in CI).
bash "$root/scripts/vivid_vm.sh"

# The boards' TensorFlow Lite runtime, tflite_runtime's aarch64 build, run under QEMU's user-mode
# emulator on the shipped models (tests/test_aarch64_models.py): scripts/aarch64_root.sh
# downloads an aarch64 Python from Debian's packages, QEMU and the wheels into a cache, and
# installs nothing (one line where it cannot; that test is then skipped, and fails in CI).
bash "$root/scripts/aarch64_root.sh" \
  || echo '[test] scripts/aarch64_root.sh failed: the aarch64 model test will be skipped (in CI: fail)'

# pytest exits 5 when it ran no test: that is a failure, except that a -k or -m that matches
# none of a run's tests may leave that run empty.
check_ran_tests() {
  local status=$1 run=$2
  shift 2
  if [ "$status" = 5 ]; then
    case " $* " in
      *' -k'* | *' -m'*) echo "[test] the $run has none of the selected tests"; return 0 ;;
    esac
    echo "[test] the $run collected no tests: that is a failure" >&2
    return 1
  fi
  return "$status"
}

# The plain workspaces are made in here, removed when the script ends.
scratch=$(mktemp -d "${TMPDIR:-/tmp}/py_vision_test.XXXXXX")
trap 'rm -rf "$scratch"' EXIT

# Run the package's tests as a ROS user does, where the package alone is (docs/ros.md): a copy
# of py_vision/ in a new workspace's src/ (a temporary directory, nothing of the checkout
# around it: a package test that reads outside py_vision/ fails here), `colcon build`, `colcon
# test` with the arguments given to pytest, and `colcon test-result --verbose`. In the current
# environment less PY_VISION_INSTALL: the tests find the workspace's install as `colcon test`
# gives it to them. Status 5 when pytest ran no test.
# Usage: workspace_test COLCON RUN PYTEST_ARGS...
workspace_test() {
  local colcon=$1 run=$2 ws status=0 summary
  shift 2
  ws=$(mktemp -d "$scratch/workspace.XXXXXX")
  mkdir "$ws/src"
  tar -C "$root" --exclude=__pycache__ --exclude=.pytest_cache --exclude=.hypothesis -cf - \
    py_vision | tar -C "$ws/src" -xf -
  echo "[test] $run: colcon build and colcon test of py_vision alone, in $ws"
  (cd "$ws" && env -u PY_VISION_INSTALL "$colcon" build >build.log 2>&1) \
    || { cat "$ws/build.log" >&2; echo "[test] $run: colcon build failed" >&2; return 1; }
  (cd "$ws" && env -u PY_VISION_INSTALL "$colcon" test --event-handlers console_direct+ \
    --pytest-args "$@") || status=$?
  [ "$status" = 0 ] || { echo "[test] $run: colcon test failed ($status)" >&2; return 1; }
  summary=$(cd "$ws" && "$colcon" test-result --verbose) || status=$?
  echo "$summary"
  # 'Summary: 1471 tests, 0 errors, 1 failures, 3 skipped'
  if grep -q '^Summary: 0 tests' <<<"$summary"; then
    return 5
  fi
  return "$status"
}

status=0
# -rs: each skipped test is listed with its reason at the end, and --durations the slowest
# tests with their times, which say where a run's time goes (in every run).
report=(-rs --durations=15)
# Two pytest-xdist workers (PY_VISION_TEST_WORKERS: another number, 0 for none): most tests
# wait on nodes, DDS and the VM, so two at once on two cores take about half the time. The
# harness keeps them apart (docs/tests.md#running-in-parallel-and-the-time-it-takes), and
# conftest.py's scheduler gives the vivid VM's tests to one worker, so the VM boots once.
report+=(-n "${PY_VISION_TEST_WORKERS:-2}" --dist load)
workspace_test "$root/.venv/bin/colcon" 'main run' "${report[@]}" "$@" || status=$?
check_ran_tests "$status" 'main run (py_vision)' "$@" || exit 1
status=0
.venv/bin/python -m pytest tests petalinux/test -p no:cacheprovider "${report[@]}" "$@" \
  || status=$?
check_ran_tests "$status" "main run (the repository's tests)" "$@" || exit 1

# The boards' software: Python 3.10 with numpy 1.23.3 and OpenCV 4.6.0, and their ROS 2 Humble
# (rclpy 3.3.2, launch_ros 0.19.2, Fast DDS 2.6.0) unpacked from its tarball. Every package test
# but the browser ones (PY_VISION_BROWSER=off leaves them out: no Playwright there) runs again
# there, with that Humble's colcon in a plain workspace (workspace_test), against the package
# built there, so that the nodes and the `ros2 launch` these tests start run there too.
# Humble's shared libraries come from Debian (and zstd unpacks it).
board_run() {
  local setup=0 status=0 missing
  install_tool 'libspdlog1.10 libfmt9 libtinyxml2-9 libyaml-0-2 libssl3 zstd' \
    "the board-version run's ROS 2 Humble"
  echo "[test] board-version run: Python 3.10, numpy 1.23.3, OpenCV 4.6.0, ROS 2 Humble" \
    '(.venv-board)'
  bash scripts/setup.sh --board || setup=$?
  case $setup in
    0) ;;
    3) missing='no Python 3.10 on this machine' ;;
    4) missing="the boards' ROS 2 Humble was not found" ;;
    *) return "$setup" ;;
  esac
  if [ -n "${missing:-}" ]; then
    if [ "$in_ci" = true ]; then
      echo "[test] FAILED: the board-version run is required in CI: $missing (see above)" >&2
      return 1
    fi
    echo "[test] SKIPPED the board-version run: $missing (see above); the main run passed," \
      'but nothing was tested on the boards'"'"' software' >&2
    return 0
  fi
  (
    # shellcheck disable=SC1091
    . scripts/board_env.sh
    python -c 'import sys, cv2, numpy, rclpy, launch_ros
print("[test] Python", sys.version.split()[0], "numpy", numpy.__version__, "OpenCV",
      cv2.__version__, "ROS 2", __import__("os").environ["ROS_DISTRO"], "from",
      rclpy.__file__.split("/lib/python")[0])'
    # This run is the image: what an image built with petalinux/ has imports here at its
    # versions, and what no board has (onnxruntime, ai_edge_litert) does not
    # (petalinux/image_python.txt). Otherwise no test runs.
    python petalinux/check_board_env.py \
      || { echo '[test] FAILED: the board-version run is not the image (see above)' >&2; exit 1; }
    # PY_VISION_VIVID=off: the vivid VM's tests are the main run's (docs/vivid.md says why);
    # PY_VISION_LINTERS=off: so are the linters, whose answer is the same on every version.
    # PY_VISION_BOARD_RUN=1: a test that has a fallback for what the image has (vision_msgs)
    # takes the image's path, never the fallback.
    PY_VISION_BROWSER=off PY_VISION_VIVID=off PY_VISION_LINTERS=off PY_VISION_BOARD_RUN=1 \
      workspace_test "$root/.venv-board/bin/colcon" 'board-version run' --ignore=test/browser \
      "${report[@]}" "$@"
  ) || status=$?
  check_ran_tests "$status" 'board-version run' "$@"
}
board_run "$@"
