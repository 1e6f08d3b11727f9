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
# py_vision's bbappend (petalinux/meta-user/ in the py_vision repository), which
# petalinux/enable_ros.py places in a PetaLinux 2023.2 project's project-spec/meta-user layer.
#
# Fast DDS 2.6.0 as PetaLinux 2023.2's meta-ros builds it (meta-ros2-humble's
# generated-recipes/fastrtps/fastrtps_2.6.0-3.bb), with eProsima's fix "Improve SHM
# resilience to crashing participants": a shared-memory port always takes a message off its
# head, so that one from a process that has already gone no longer blocks every later one
# (the "node nobody hears" of py_vision's docs/boards.md). Fast-DDS commit df904f30, pull
# requests #3759 and #3765, released in Fast DDS 2.6.6: the patch in files/, as git
# format-patch wrote it, with its Upstream-Status line added.
#
# The file name names that recipe's exact version: this applies to fastrtps 2.6.0-3 and to no
# other Fast DDS. On a meta-ros with another version bitbake finds no recipe for it and, since
# PetaLinux sets BB_DANGLINGAPPENDS_WARNONLY, only warns ("No recipes in default available
# for: ...") and builds that Fast DDS without the patch (petalinux/README.md).

FILESEXTRAPATHS:prepend := "${THISDIR}/files:"

SRC_URI += "file://0001-Improve-SHM-resilience-to-crashing-participants-3765.patch"
