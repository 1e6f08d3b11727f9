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


"""The tests' own harness: what its helpers promise the tests that use them."""

import ros_harness


def test_a_peer_stops_spinning_before_its_node_is_destroyed(domain_id):
    # A peer whose executor thread still spins while its node is destroyed raises
    # InvalidHandle in that thread (seen as a warning in a fresh-clone run).
    peer = ros_harness.RosPeer(domain_id)
    spinning_at_destroy = []
    destroy = peer.node.destroy_node

    def recorded_destroy():
        spinning_at_destroy.append(peer._thread.is_alive())
        return destroy()

    peer.node.destroy_node = recorded_destroy
    peer.close()
    assert spinning_at_destroy == [False]
