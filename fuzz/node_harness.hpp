// The node targets' harness (fuzz_robot_node, fuzz_main_robot): a node on its ports,
// on a NodeShell over the in-process transport, as the process runs it. The shell,
// the transport and the ports live across inputs (their decode buffers are reserved
// once: megabytes); the node is reset to a pristine copy before each input, so an
// input's outcome depends on it alone.
#pragma once

#include <cstdint>
#include <cstdlib>
#include <iterator>
#include <string>
#include <utility>

#include "elaslam/transport/inprocess_transport.hpp"
#include "elaslam/transport/node_shell.hpp"
#include "fuzz_input.hpp"

namespace elaslam::fuzz {

template <class Node, template <class> class Ports>
struct NodeHarness {
  NodeHarness(const char* name, Node node_at_start)
      : shell(bus, [this, name] {
          transport::ShellOptions so(name, "", nullptr);
          so.clock = [this] { return clock += 1000; };
          return so;
        }()),
        pristine(std::move(node_at_start)) {
    if (!ports.open()) std::abort();
  }

  /// The node as at start, then every record of the input on its channel, each
  /// dispatched (with what the node publishes in answer) before the next.
  template <std::size_t N>
  void run(const std::uint8_t* data, std::size_t size, const std::string (&channels)[N]) {
    node = pristine;
    clock = 1'700'000'000'000'000;
    for_each_record(data, size, N, [&](const Record& r) {
      bus.publish(channels[r.channel], r.data, r.size);
      bus.dispatch_all();
    });
  }

  transport::InProcessTransport bus;
  std::int64_t clock = 0;
  transport::NodeShell shell;
  const Node pristine;
  Node node{pristine};
  Ports<transport::NodeShell> ports{shell, node};
};

}  // namespace elaslam::fuzz
