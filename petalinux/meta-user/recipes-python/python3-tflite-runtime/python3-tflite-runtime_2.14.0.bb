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
#
# py_vision's recipe (petalinux/meta-user/ in the py_vision repository), which
# petalinux/enable_ros.py places in a PetaLinux 2023.2 project's project-spec/meta-user layer.
# Edit it there and run the tool again: a copy edited in the project is replaced only when
# the tool is run with --replace.
#
# The TensorFlow Lite runtime (the tflite_runtime module) for the image's Python 3.10 on
# aarch64, which py_vision's hand_signs and faces steps run their .tflite models on. It is
# Google's prebuilt wheel from PyPI, installed as it is: nothing is compiled and nothing is
# fetched on the board. petalinux/README.md says why a wheel rather than a build from source.

SUMMARY = "TensorFlow Lite runtime for Python (tflite_runtime), Google's prebuilt aarch64 wheel"
DESCRIPTION = "The tflite_runtime Python module: the TensorFlow Lite interpreter without the \
rest of TensorFlow, from the tflite-runtime ${PV} wheel that Google publishes on PyPI for \
CPython 3.10 on aarch64 Linux (manylinux_2_34), installed unchanged."
HOMEPAGE = "https://www.tensorflow.org/lite/"
SECTION = "devel/python"

# The licences of what the wheel installs. Its METADATA says "License: Apache 2.0", and it
# carries no licence file. Apache-2.0 covers TensorFlow Lite itself and the Apache-2.0
# libraries built into its extension module (abseil, flatbuffers, gemmlowp, ruy). That module,
# _pywrap_tensorflow_interpreter_wrapper.so, also holds these libraries, linked in statically
# (their symbols are in it), each under its own licence:
# - XNNPACK (its kernels): BSD-3-Clause;
# - pthreadpool and cpuinfo: BSD-2-Clause;
# - Eigen: MPL-2.0 (TensorFlow builds it with EIGEN_MPL2_ONLY, so no LGPL part of it is in;
#   Eigen::half's float conversions keep Fabian Giesen's notice, a BSD-style permission that
#   asks nothing);
# - farmhash, and FP16 (XNNPACK's half-precision conversions): MIT;
# - pybind11 (the Python binding): BSD-3-Clause;
# - fft2d, Takuya Ooura's FFT package: its own licence, use, copying and changes for any
#   purpose without fee, distribution of the original package. Yocto has no text of it:
#   files/readme2d.txt is the package's own readme with it (lines 67 to 70), unchanged from
#   the OouraFFT-1.0 archive TensorFlow builds fft2d from
#   (https://github.com/petewarden/OouraFFT, tag v1.0, commit c6fd2dd6; TensorFlow Lite's
#   CMake build names this file as fft2d's licence).
# The generic texts are the ones every Yocto build has (COMMON_LICENSE_DIR).
LICENSE = "Apache-2.0 & BSD-3-Clause & BSD-2-Clause & MPL-2.0 & MIT & Ooura-fft2d"
LIC_FILES_CHKSUM = "\
    file://${COMMON_LICENSE_DIR}/Apache-2.0;md5=89aea4e17d99a7cacdbeed46a0096b10 \
    file://${COMMON_LICENSE_DIR}/BSD-3-Clause;md5=550794465ba0ec5312d6919e203a55f9 \
    file://${COMMON_LICENSE_DIR}/BSD-2-Clause;md5=cb641bc04cda31daea161b1bc15da69f \
    file://${COMMON_LICENSE_DIR}/MPL-2.0;md5=815ca599c9df247a0c7f619bab123dad \
    file://${COMMON_LICENSE_DIR}/MIT;md5=0835ade698e0bcf8506ecda2f7b4f302 \
    file://readme2d.txt;beginline=67;endline=70;md5=4f01a5fd045b8e9c56c61a218356fea7 \
"
NO_GENERIC_LICENSE[Ooura-fft2d] = "readme2d.txt"

# The wheel, pinned by its sha256 (the one PyPI lists for this file). Not unpacked by the
# fetcher (a .whl is not an archive type it knows): it is copied into ${WORKDIR} as it is.
SRC_URI = "https://files.pythonhosted.org/packages/04/dd/a701667be92bb884644eeec91ebbde57e197d27d9a79241169b6ce15e1ad/tflite_runtime-2.14.0-cp310-cp310-manylinux_2_34_aarch64.whl"
SRC_URI[sha256sum] = "d38c6885f5e9673c11a61ccec5cad7c032ab97340718d26b17794137f398b780"
# fft2d's licence text (above), from files/: the licence checks read it from ${S}.
SRC_URI += "file://readme2d.txt"

WHEEL = "tflite_runtime-${PV}-cp310-cp310-manylinux_2_34_aarch64.whl"
S = "${WORKDIR}"

# python_pep517 installs a wheel with pypa/installer into the target's site-packages (the
# target's sysconfig, through python3targetconfig); its do_compile would build the wheel from
# source. Here do_compile puts the prebuilt wheel where that do_install looks for it.
inherit python_pep517 python3native python3-dir setuptools3-base

do_compile() {
    install -m 0644 ${WORKDIR}/${WHEEL} ${PEP517_WHEEL_PATH}/
}

# The wheel holds machine code for little-endian aarch64 with glibc (manylinux): nothing else
# can run it. The pattern matches HOST_SYS from its start: aarch64-<vendor>-linux, not
# big-endian aarch64_be-<vendor>-linux; a musl build is refused by the second line.
COMPATIBLE_HOST = "aarch64-.*-linux"
COMPATIBLE_HOST:libc-musl = "null"

python () {
    # A cp310 wheel's extension module loads into Python 3.10 alone: refuse any other Python
    # at parse time rather than ship a module that fails on import.
    if d.getVar('PYTHON_BASEVERSION') != '3.10':
        raise bb.parse.SkipRecipe('the tflite-runtime wheel is built for CPython 3.10 (cp310); '
                                  'this build has Python %s' % d.getVar('PYTHON_BASEVERSION'))
}

# Shipped byte for byte as the wheel has it: its extension module keeps its symbol table
# (about 1 MB of its 6.5 MB), and the files on the board are the ones the wheel's RECORD
# lists and the ones tested elsewhere from the same wheel.
INHIBIT_PACKAGE_STRIP = "1"
INHIBIT_PACKAGE_DEBUG_SPLIT = "1"

# What the wheel needs at run time. Its METADATA: "Requires-Dist: numpy >=1.23.2" (the image's
# python3-numpy is 1.23.3). Its Python code imports ctypes, enum, os, platform, sys, typing and
# abc (python3-ctypes, the rest python3-core). Its extension module's NEEDED libraries are
# libc.so.6, libm.so.6, libdl.so.2, libpthread.so.0 (glibc), libstdc++.so.6 and libgcc_s.so.1:
# the packaging step adds those from the shared library table, as for any binary.
RDEPENDS:${PN} += "python3-core python3-ctypes python3-numpy"
