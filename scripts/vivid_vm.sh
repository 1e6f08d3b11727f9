#!/usr/bin/env bash
# Set up what the capture tests on the kernel's vivid driver need (py_vision/test/vivid_vm.py,
# docs/vivid.md), on Debian:
#   - QEMU (qemu-system-x86), busybox (virtme-ng's initramfs) and kmod (modprobe), as root
#     with apt; virtme-ng itself comes from requirements-test.txt (scripts/setup.sh --test);
#   - Debian's kernel (the package linux-image-amd64 depends on), downloaded with apt and
#     unpacked into a cache, not installed: nothing of this machine's own boot changes. Only
#     what the VM loads is unpacked (media, virtio, 9p, file systems), about 90 MB.
# The cache is $PY_VISION_VIVID_CACHE, else ${XDG_CACHE_HOME:-~/.cache}/py_vision/vivid.
# Where something cannot be set up it says so in one line and exits 0: the vivid tests are
# then skipped with the reason (and fail in CI, CI=true, where everything is installed,
# whatever it upgrades). Safe to run again: it only does what is missing.
set -euo pipefail
log=/tmp/py_vision-apt.log
cache=${PY_VISION_VIVID_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/py_vision/vivid}
in_ci=false
[ "${CI:-}" = true ] && in_ci=true
# apt waits for another apt (another test run, an unattended upgrade) instead of failing.
apt_wait=(-o DPkg::Lock::Timeout=300)

have() { PATH=$PATH:/usr/sbin:/sbin command -v "$1" >/dev/null 2>&1; }

install_packages() {
  local packages=() plan upgrades
  have qemu-system-x86_64 || packages+=(qemu-system-x86)
  have busybox || packages+=(busybox-static)
  have modprobe || packages+=(kmod)
  [ ${#packages[@]} = 0 ] && return 0
  if [ "$(id -u)" != 0 ] || ! have apt-get; then
    echo "[vivid] missing ${packages[*]}: the vivid tests will be skipped (in CI: fail)" \
      "(as root: apt-get install --no-install-recommends ${packages[*]})"
    return 1
  fi
  if [ "$in_ci" = true ]; then
    apt-get "${apt_wait[@]}" update -qq >$log 2>&1 || true
  elif ! plan=$(apt-get install -s --no-install-recommends --no-upgrade "${packages[@]}" \
      2>$log); then
    echo "[vivid] missing ${packages[*]} and apt cannot install them (see $log;" \
      'apt-get update may help): the vivid tests will be skipped'
    return 1
  elif upgrades=$(grep '^Inst [^ ]* \[' <<<"$plan"); then
    echo "[vivid] missing ${packages[*]}, and installing them would upgrade" \
      "$(wc -l <<<"$upgrades") installed package(s): left as they are, the vivid tests" \
      "will be skipped; to run them: apt-get install --no-install-recommends ${packages[*]}"
    return 1
  fi
  echo "[vivid] installing ${packages[*]} for the vivid tests"
  DEBIAN_FRONTEND=noninteractive apt-get "${apt_wait[@]}" install -y -qq \
    --no-install-recommends --no-upgrade "${packages[@]}" >>$log 2>&1 \
    || { echo "[vivid] could not install ${packages[*]} (see $log)"; return 1; }
}

# The kernel package linux-image-amd64 stands for (linux-image-<version>-amd64), unpacked into
# $cache/<package>/ with its modules indexed (depmod); .complete marks it usable.
unpack_kernel() {
  local package work
  if ! have apt-cache || ! have dpkg-deb; then
    echo '[vivid] no apt here to fetch Debian'"'"'s kernel: the vivid tests will be skipped' \
      '(or name a kernel image: PY_VISION_VIVID_KERNEL=/boot/vmlinuz-...)'
    return 1
  fi
  package=$(apt-cache depends linux-image-amd64 2>/dev/null \
    | awk '$1 == "Depends:" && $2 ~ /^linux-image-/ {print $2; exit}')
  if [ -z "$package" ] && [ "$(id -u)" = 0 ] && [ "$in_ci" = true ]; then
    apt-get "${apt_wait[@]}" update -qq >>$log 2>&1 || true
    package=$(apt-cache depends linux-image-amd64 2>/dev/null \
      | awk '$1 == "Depends:" && $2 ~ /^linux-image-/ {print $2; exit}')
  fi
  if [ -z "$package" ]; then
    echo '[vivid] apt knows no linux-image-amd64 (apt-get update may help): the vivid tests' \
      'will be skipped'
    return 1
  fi
  [ -f "$cache/$package/.complete" ] && return 0
  if ! have depmod; then
    echo '[vivid] no depmod (Debian package kmod) to index the kernel'"'"'s modules: the' \
      'vivid tests will be skipped'
    return 1
  fi
  echo "[vivid] unpacking Debian's $package into $cache for the vivid tests"
  mkdir -p "$cache"
  work=$(mktemp -d "$cache/.unpack.XXXXXX")
  # apt's sandbox user may not write to the cache: download as the caller.
  if ! (cd "$work" && apt-get -o APT::Sandbox::User="$(id -un)" download "$package" \
      >>$log 2>&1); then
    rm -rf "$work"
    echo "[vivid] could not download $package (see $log): the vivid tests will be skipped"
    return 1
  fi
  mkdir "$work/root"
  dpkg-deb --fsys-tarfile "$work"/*.deb | tar -x -C "$work/root" --wildcards \
    './boot/vmlinuz-*' '*/modules/*/modules.*' '*/kernel/drivers/media/*' \
    '*/kernel/drivers/virtio/*' '*/kernel/drivers/char/*' '*/kernel/fs/*' '*/kernel/net/9p/*' \
    '*/kernel/lib/*' '*/kernel/crypto/*' '*/kernel/arch/*'
  local version
  version=$(basename "$work"/root/boot/vmlinuz-*)
  version=${version#vmlinuz-}
  PATH=$PATH:/usr/sbin:/sbin depmod -b "$work/root" "$version"
  touch "$work/root/.complete"
  # Older kernels go: a cache holds the one apt offers now.
  rm -rf "${cache:?}"/linux-image-*
  mv "$work/root" "$cache/$package"
  rm -rf "$work"
}

status=0
install_packages || status=1
if [ -z "${PY_VISION_VIVID_KERNEL:-}" ]; then
  unpack_kernel || status=1
fi
[ "$status" = 0 ] && echo "[vivid] ready: QEMU, busybox, kmod and $(ls -d "$cache"/linux-image-* \
  2>/dev/null | head -1 || echo "$PY_VISION_VIVID_KERNEL")"
exit 0
