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

"""What `ros2 param set/get/describe` do, through a test peer: the node's parameter services."""

import time

from rcl_interfaces.msg import Parameter as ParameterMsg, ParameterType, ParameterValue
from rcl_interfaces.srv import (
    DescribeParameters, GetParameters, ListParameters, SetParameters)
from ros_harness import wait_until


# wait_for_service() says this side has found the node's service, not that the node has found
# this client's reply reader: Fast DDS drops a reply sent before it has (the node logs 'failed to
# send response (timeout)') and the request would wait forever. Parameter requests here are
# idempotent (the same set, get or describe again), so one unanswered for a few seconds is sent
# again, as a user repeats `ros2 param get`.
RESEND_AFTER_S = 4.0
ANSWER_WITHIN_S = 20.0
DISCOVERED_WITHIN_S = 20.0


class Unreached(AssertionError):
    """
    DDS did not connect the peer to the node's service.

    The peer found no ready service of the node within DISCOVERED_WITHIN_S, or no answer came
    within ANSWER_WITHIN_S; the message says what the peer's graph held then.
    """


def _call(peer, node_name, service_type, service, request):
    client = peer.node.create_client(service_type, '/%s/%s' % (node_name, service))
    try:
        if not client.wait_for_service(timeout_sec=DISCOVERED_WITHIN_S):
            raise Unreached('no %s service on %s (%s)' % (
                service, node_name, _graph(peer, node_name, service)))
        deadline = time.monotonic() + ANSWER_WITHIN_S
        while True:
            future = client.call_async(request)
            left = deadline - time.monotonic()
            try:
                wait_until(future.done, max(0.1, min(RESEND_AFTER_S, left)),
                           what='%s reply from %s' % (service, node_name))
                return future.result()
            except AssertionError:
                client.remove_pending_request(future)
                if left <= RESEND_AFTER_S:
                    raise Unreached('timed out after %.1f s waiting for %s reply from %s (%s)' % (
                        ANSWER_WITHIN_S, service, node_name,
                        _graph(peer, node_name, service))) from None
    finally:
        peer.node.destroy_client(client)  # a test calling many times keeps one client at a time


def _graph(peer, node_name, service):
    """
    Say what this peer's graph holds for /node_name/service, and every node it sees.

    A client finds a service ready once the graph holds as many request readers as reply
    writers for it, and it has matched both (rmw_fastrtps): the endpoints listed here, by node,
    say which of these failed.
    """
    name = '/%s/%s' % (node_name, service)

    def owners(infos):
        return sorted('%s/%s' % (info.node_namespace.rstrip('/'), info.node_name)
                      for info in infos) or 'none'
    try:
        readers = peer.node.get_subscriptions_info_by_topic('rq%sRequest' % name, no_mangle=True)
        writers = peer.node.get_publishers_info_by_topic('rr%sReply' % name, no_mangle=True)
        nodes = sorted(ns.rstrip('/') + '/' + each
                       for each, ns in peer.node.get_node_names_and_namespaces())
    except Exception as error:  # say so in the failure, rather than replace it
        return 'the graph could not be read: %s: %s' % (type(error).__name__, error)
    return 'in the graph, request readers of %s: %s; reply writers: %s; nodes: %s' % (
        name, owners(readers), owners(writers), nodes)


def parameter_value(value):
    """Return a ParameterValue of the Python value's type, as `ros2 param set` parses it."""
    if isinstance(value, bool):
        return ParameterValue(type=ParameterType.PARAMETER_BOOL, bool_value=value)
    if isinstance(value, str):
        return ParameterValue(type=ParameterType.PARAMETER_STRING, string_value=value)
    if isinstance(value, float):
        return ParameterValue(type=ParameterType.PARAMETER_DOUBLE, double_value=value)
    return ParameterValue(type=ParameterType.PARAMETER_INTEGER, integer_value=value)


def set_parameter(peer, node_name, name, value):
    """Set one parameter; return the SetParametersResult (successful, reason)."""
    request = SetParameters.Request(
        parameters=[ParameterMsg(name=name, value=parameter_value(value))])
    return _call(peer, node_name, SetParameters, 'set_parameters', request).results[0]


def _one_each(peer, node_name, service, names, answer):
    # rclpy answers nothing at all when one of the names is not declared: say so, with who
    # in the graph could have answered, rather than fail later on an empty list.
    if len(answer) != len(names):
        raise AssertionError(
            '%s of %s answered %d item(s) for %d name(s) %s: one of them is not declared (%s)' % (
                service, node_name, len(answer), len(names), list(names),
                _graph(peer, node_name, service)))
    return answer


def get_parameters(peer, node_name, names):
    """Return the ParameterValues of names, in order (AssertionError: one is not declared)."""
    request = GetParameters.Request(names=list(names))
    return _one_each(peer, node_name, 'get_parameters', names,
                     _call(peer, node_name, GetParameters, 'get_parameters', request).values)


def describe_parameters(peer, node_name, names):
    """Return the ParameterDescriptors of names, in order (AssertionError: one is not declared)."""
    request = DescribeParameters.Request(names=list(names))
    return _one_each(peer, node_name, 'describe_parameters', names,
                     _call(peer, node_name, DescribeParameters, 'describe_parameters',
                           request).descriptors)


def list_parameters(peer, node_name):
    """Return the names of every parameter the node has declared (`ros2 param list`)."""
    return list(_call(peer, node_name, ListParameters, 'list_parameters',
                      ListParameters.Request()).result.names)
