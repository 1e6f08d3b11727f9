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
# generated-recipes/fastrtps/fastrtps_2.6.0-3.bb), with two patches of its shared-memory
# transport from files/, applied in this order (the second changes a line the first adds):
#
# 1. eProsima's fix "Improve SHM resilience to crashing participants": a shared-memory port
#    always takes a message off its head, so that one from a process that has already gone
#    no longer blocks every later one (the "node nobody hears" of py_vision's
#    docs/boards.md). Fast-DDS commit df904f30, pull requests #3759 and #3765, released in
#    Fast DDS 2.6.6: as git format-patch wrote it, with its Upstream-Status line added.
# 2. The fix of that fix's self-deadlock: df904f30 makes listener_processing_stop() lock the
#    port's empty_cv_mutex, which get_and_remove_blocked_processing() already holds when it
#    calls it. Fast DDS' interprocess mutex gives up after 1 s, the exception is swallowed,
#    the listener stays marked as processing, and recover_blocked_processing() loops, 1 s a
#    pass, after a participant crashed mid-processing: the very case the first patch is for.
#    Fast-DDS commit f6f665a4 (pull request #6497, issue #6485; not merged when this was
#    written), limited to its source file: see the patch's header.
#
# The file name names that recipe's exact version: this applies to fastrtps 2.6.0-3 and to no
# other Fast DDS. On a meta-ros with another version bitbake finds no recipe for it and, since
# PetaLinux sets BB_DANGLINGAPPENDS_WARNONLY, only warns ("No recipes in default available
# for: ...") and builds that Fast DDS without the patches (petalinux/README.md). Fast DDS
# 2.6.6 and later have the first as released, and up to 2.6.12 (and 3.3.0) not the second.

FILESEXTRAPATHS:prepend := "${THISDIR}/files:"

# 1. df904f30: SHM resilience to crashing participants.
SRC_URI += "file://0001-Improve-SHM-resilience-to-crashing-participants-3765.patch"
# 2. f6f665a4: no second lock of empty_cv_mutex in the recovery (needs 1 applied).
SRC_URI += "file://0002-Fix-SharedMem-self-deadlock-in-blocked-processing-re.patch"
