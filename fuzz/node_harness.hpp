// SPDX-License-Identifier: Apache-2.0
// The node targets' harness (fuzz_robot_node, fuzz_main_robot, fuzz_viewer): a node
// on its ports, on a NodeShell over the in-process transport, as the process runs
// it. The shell, the transport and the ports live across inputs (their decode
// buffers are reserved once: megabytes); the node is made anew before each input
// (`make`, then moved in: the ports keep their reference), so an input's outcome
// depends on it alone. Made, not copied from a pristine one: a copy copies every
// scratch buffer element by element under the coverage instrumentation (the ELA
// gate's pairwise blocks: 58 % of fuzz_robot_node's time), a move swaps pointers.
// ShellRig: a node, its shell and its ports made whole over another transport
// (fuzz_datagrams: the receive path from raw datagrams up).
#pragma once

#include <cstdint>
#include <cstdlib>
#include <functional>
#include <iterator>
#include <string>
#include <utility>

#include "elaslam/transport/inprocess_transport.hpp"
#include "elaslam/transport/node_shell.hpp"
#include "fuzz_input.hpp"

namespace elaslam::fuzz {

/// A fuzzed node's shell options: its name, no log, and a clock that advances 1 ms
/// each time it is read (*clock, which the harness owns and sets at each start).
inline transport::ShellOptions ticking_options(const char* name, std::int64_t* clock) {
  transport::ShellOptions so(name, "", nullptr);
  so.clock = [clock] { return *clock += 1000; };
  return so;
}

template <class Node, template <class> class Ports>
struct NodeHarness {
  NodeHarness(const char* name, std::function<Node()> make_node)
      : shell(bus, ticking_options(name, &clock)),
        make(std::move(make_node)) {
    if (!ports.open()) std::abort();
  }

  /// The node as at start, then every record of the input on its channel, each
  /// dispatched (with what the node publishes in answer) before the next.
  template <std::size_t N>
  void run(const std::uint8_t* data, std::size_t size, const std::string (&channels)[N]) {
    node = make();
    clock = 1'700'000'000'000'000;
    for_each_record(data, size, N, [&](const Record& r) {
      bus.publish(channels[r.channel], r.data, r.size);
      bus.dispatch_all();
    });
  }

  transport::InProcessTransport bus;
  std::int64_t clock = 0;
  transport::NodeShell shell;
  const std::function<Node()> make;
  Node node{make()};
  Ports<transport::NodeShell> ports{shell, node};
};

/// The datagram target's node (fuzz_datagrams.cpp): a node on its ports on a NodeShell
/// over a transport that the caller keeps, made whole, as NodeHarness makes its shell
/// and ports, with the node anew. Not movable: the shell's clock and the ports point
/// into it. untouched() says whether it is still as made (no message reached a handler,
/// nothing was published): then the next input may use it again, and depends on
/// nothing before it; else the caller makes a new one.
template <class Node, template <class> class Ports>
struct ShellRig {
  static constexpr std::int64_t kEpoch = 1'700'000'000'000'000;  // [us] the shell's clock at the start

  ShellRig(transport::Transport& transport, const char* name, Node made)
      : shell(transport, ticking_options(name, &clock)),
        node(std::move(made)) {
    if (!ports.open()) std::abort();
  }
  ShellRig(const ShellRig&) = delete;
  ShellRig& operator=(const ShellRig&) = delete;

  bool untouched() const {
    const transport::ShellCounters c = shell.counters();
    return c.inputs.received == 0 && c.published == 0 && c.publish_errors == 0;
  }

  std::int64_t clock = kEpoch;
  transport::NodeShell shell;
  Node node;
  Ports<transport::NodeShell> ports{shell, node};
};

}  // namespace elaslam::fuzz
