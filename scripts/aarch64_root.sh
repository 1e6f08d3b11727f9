#!/usr/bin/env bash
# Set up what tests/test_aarch64_models.py needs to run the boards' TensorFlow Lite runtime,
# tflite_runtime 2.14.0's aarch64 build, on this x86-64 machine (docs/tests.md, "The boards'
# TensorFlow Lite runtime under QEMU"):
#   - an aarch64 Python 3.11 from Debian 12's arm64 packages, and QEMU's user-mode emulator
#     qemu-aarch64-static (Debian's qemu-user-static), fetched with `apt-get download` and
#     unpacked into a cache, not installed. apt works there on a state of its own in the cache
#     (this machine's Debian mirrors, for arm64 and amd64): nothing of the machine's apt or dpkg
#     changes, and root is not needed;
#   - from PyPI (`pip download`, nothing installed): tflite-runtime 2.14.0's aarch64 wheel for
#     Python 3.10, the one the boards' image installs (its name and sha256 are checked against
#     petalinux's recipe when the checkout has it), and for Python 3.11, the one that runs here
#     (Debian 12 has no Python 3.10); numpy 1.23.3, the boards', for Python 3.11 on aarch64; and
#     the same two for Python 3.11 on x86-64. Every wheel is checked against its sha256 below.
# The cache is $PY_VISION_AARCH64_CACHE, else ${XDG_CACHE_HOME:-~/.cache}/py_vision/aarch64.
# Where something cannot be set up it says so in one line (also in the cache's problem.txt,
# which the test shows) and exits 0: the test is then skipped with the reason, and fails in CI.
# Run again, it does nothing while the cache is complete for the pins below.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cache=${PY_VISION_AARCH64_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/py_vision/aarch64}
log=$cache/setup.log
python=${PYTHON:-$root/.venv/bin/python}
[ -x "$python" ] || python=python3

# The wheels: each file's name, and on the next line its sha256 (PyPI's). The first is the
# image's (petalinux/meta-user/recipes-python/python3-tflite-runtime/: SRC_URI and
# SRC_URI[sha256sum]).
image_wheel=tflite_runtime-2.14.0-cp310-cp310-manylinux_2_34_aarch64.whl
wheels="$image_wheel
  d38c6885f5e9673c11a61ccec5cad7c032ab97340718d26b17794137f398b780
tflite_runtime-2.14.0-cp311-cp311-manylinux_2_34_aarch64.whl
  ce9fa5d770a9725c746dcbf6f59f3178233b3759f09982e8b2db8d2234c333b0
numpy-1.23.3-cp311-cp311-manylinux_2_17_aarch64.manylinux2014_aarch64.whl
  bdc9febce3e68b697d931941b263c59e0c74e8f18861f4064c1f712562903411
tflite_runtime-2.14.0-cp311-cp311-manylinux2014_x86_64.whl
  195ab752e7e57329a68e54dd3dd5439fad888b9bff1be0f0dc042a3237a90e4d
numpy-1.23.3-cp311-cp311-manylinux_2_17_x86_64.manylinux2014_x86_64.whl
  301c00cf5e60e08e04d842fc47df641d4a181e651c7135c50dc2762ffe293dbd"
# Debian 12's arm64 packages an aarch64 Python 3.11 needs to run numpy and tflite_runtime
# (whose library needs libstdc++): the same glibc, 2.36, as PetaLinux 2023.2's.
suite=bookworm
packages='libc6 libgcc-s1 libstdc++6 zlib1g libexpat1 libffi8 libssl3 libbz2-1.0 liblzma5
  libcrypt1 libuuid1 libpython3.11-minimal libpython3.11-stdlib python3.11-minimal'
stamp=$(printf '%s\n' "$wheels" "$suite" "$packages" | sha256sum | cut -c1-16)

problem() {
  trap - ERR
  { mkdir -p "$cache" && echo "$*" >"$cache/problem.txt" && rm -f "$cache/.complete"; } \
    2>/dev/null || true
  echo "[aarch64] $*: the aarch64 model test will be skipped (in CI: fail)"
  exit 0
}

have() { command -v "$1" >/dev/null 2>&1; }
# Any other command that fails is a problem of the same kind: one line, the test told, the
# run goes on (set -e would end scripts/test.sh with it).
trap 'problem "setting up failed at line $LINENO of scripts/aarch64_root.sh (exit status $?)"' ERR

# The recipe's wheel must be the one pinned here: the test then runs that build.
recipe=$(ls "$root"/petalinux/meta-user/recipes-python/python3-tflite-runtime/*.bb 2>/dev/null \
  | head -1 || true)
if [ -n "$recipe" ]; then
  url=$(sed -n 's/^SRC_URI *= *"\([^"; ]*\).*/\1/p' "$recipe" | head -1)
  sum=$(sed -n 's/^SRC_URI\[sha256sum\] *= *"\([0-9a-f]*\)".*/\1/p' "$recipe" | head -1)
  pinned=$(sed -n 2p <<<"$wheels" | tr -d ' ')
  if [ "${url##*/}" != "$image_wheel" ] || [ "$sum" != "$pinned" ]; then
    problem "the recipe ${recipe#"$root"/} installs ${url##*/} (sha256 $sum), this script" \
      "pins $image_wheel (sha256 $pinned): make them the same"
  fi
fi

if [ -f "$cache/.complete" ] && [ "$(cat "$cache/.complete")" = "$stamp" ]; then
  echo "[aarch64] ready: $cache"
  exit 0
fi
for tool in apt-get dpkg dpkg-deb sha256sum; do
  have "$tool" || problem "no $tool here (a Debian x86-64 machine is needed)"
done
[ "$(dpkg --print-architecture)" = amd64 ] \
  || problem "this machine is $(dpkg --print-architecture), not amd64 (x86-64)"
"$python" -m pip --version >/dev/null 2>&1 || problem "no pip for $python (set PYTHON)"
mkdir -p "$cache/wheels"
rm -f "$cache/.complete" "$cache/problem.txt"
: >"$log"

# The wheels, each checked against its sha256.
download_wheels() {
  local arch=$1 version=$2 platforms=() platform
  shift 2
  for platform in manylinux_2_34 manylinux_2_17 manylinux2014; do
    platforms+=(--platform "${platform}_$arch")
  done
  "$python" -m pip download --quiet --no-deps --only-binary=:all: --implementation cp \
    --python-version "$version" --abi "cp${version/./}" "${platforms[@]}" \
    --dest "$cache/wheels" "$@" >>"$log" 2>&1
}
echo "[aarch64] downloading tflite-runtime 2.14.0 and numpy 1.23.3 (aarch64, x86-64) into $cache"
download_wheels aarch64 3.10 tflite-runtime==2.14.0 \
  && download_wheels aarch64 3.11 tflite-runtime==2.14.0 numpy==1.23.3 \
  && download_wheels x86_64 3.11 tflite-runtime==2.14.0 numpy==1.23.3 \
  || problem "pip could not download the wheels (see $log)"
while read -r name && read -r sum; do
  [ -f "$cache/wheels/$name" ] || problem "pip did not download $name (see $log)"
  [ "$(sha256sum <"$cache/wheels/$name" | cut -d' ' -f1)" = "$sum" ] \
    || { rm -f "$cache/wheels/$name"; problem "$name does not have the sha256 pinned here"; }
done <<<"$wheels"

# apt on a state of its own: this machine's Debian mirrors (the ones its apt reads for its own
# release and its security updates), for Debian 12, arm64 and amd64.
state=$cache/apt
mkdir -p "$state/lists/partial" "$state/cache/archives/partial" "$state/parts" "$state/prefs"
: >"$state/status"
codename=$(. /etc/os-release && echo "${VERSION_CODENAME:-}")
targets=$(apt-get indextargets --format '$(TARGET_OF) $(REPO_URI) $(RELEASE) $(COMPONENT)' \
  2>/dev/null | sort -u)
archive=$(awk -v r="$codename" '$1 == "deb" && $3 == r && $4 == "main" {print $2; exit}' \
  <<<"$targets")
security=$(awk -v r="$codename-security" \
  '$1 == "deb" && $3 == r && $4 == "main" {print $2; exit}' <<<"$targets")
[ -n "$archive" ] || problem "apt has no Debian archive for $codename here"
keyring=/usr/share/keyrings/debian-archive-keyring.gpg
[ -f "$keyring" ] || problem "no $keyring (Debian package debian-archive-keyring)"
options="[arch=arm64,amd64 signed-by=$keyring]"
{
  echo "deb $options $archive $suite main"
  echo "deb $options $archive $suite-updates main"
  [ -z "$security" ] || echo "deb $options $security $suite-security main"
} >"$state/sources.list"
apt=(-o Dir::Etc::SourceList="$state/sources.list" -o Dir::Etc::SourceParts="$state/parts"
  -o Dir::Etc::Preferences="$state/prefs/none" -o Dir::Etc::PreferencesParts="$state/prefs"
  -o Dir::State::Lists="$state/lists" -o Dir::State::status="$state/status"
  -o Dir::Cache="$state/cache" -o APT::Architecture=amd64 -o APT::Architectures::=amd64
  -o APT::Architectures::=arm64 -o APT::Sandbox::User="$(id -un)" -o Debug::NoLocking=true)
echo "[aarch64] downloading Debian $suite's arm64 Python 3.11 and qemu-user-static"
apt-get "${apt[@]}" update >>"$log" 2>&1 || problem "apt-get update failed (see $log)"
work=$(mktemp -d "$cache/.unpack.XXXXXX")
trap 'rm -rf "$work"' EXIT
# shellcheck disable=SC2086
(cd "$work" && apt-get "${apt[@]}" download $(printf '%s:arm64 ' $packages) \
  qemu-user-static:amd64 >>"$log" 2>&1) || problem "apt-get download failed (see $log)"
mkdir "$work/aarch64" "$work/qemu"
for deb in "$work"/*_arm64.deb; do
  dpkg-deb -x "$deb" "$work/aarch64"
done
dpkg-deb --fsys-tarfile "$work"/qemu-user-static_*_amd64.deb \
  | tar -x -C "$work/qemu" ./usr/bin/qemu-aarch64-static
[ -x "$work/aarch64/usr/bin/python3.11" ] && [ -x "$work/qemu/usr/bin/qemu-aarch64-static" ] \
  || problem 'the unpacked packages have no python3.11 or qemu-aarch64-static'

# Each site folder holds the wheels that run there: numpy and tflite_runtime for Python 3.11.
for arch in aarch64 x86_64; do
  mkdir "$work/site-$arch"
  for wheel in "$cache"/wheels/*-cp311-*"$arch".whl; do
    "$python" -m zipfile -e "$wheel" "$work/site-$arch"
  done
done
rm -rf "$cache/aarch64" "$cache/site-aarch64" "$cache/site-x86_64" "$cache/qemu-aarch64-static"
mv "$work/aarch64" "$work/site-aarch64" "$work/site-x86_64" "$cache/"
mv "$work/qemu/usr/bin/qemu-aarch64-static" "$cache/"
rm -rf "$state"
echo "$stamp" >"$cache/.complete"
echo "[aarch64] ready: $cache ($(du -sh "$cache" | cut -f1))"
