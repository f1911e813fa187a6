# SPDX-License-Identifier: Apache-2.0
# Sourced by tools/run_team.sh (--hosts) and tools/loss_check.sh: network namespaces
# as hosts on one Ethernet segment, a bridge in a hub namespace, so that the check
# measures the network the team runs on.
#
#   bridge_hub HUB                     the bridge br0 in namespace HUB (made by the caller)
#   bridge_host HUB NS VETH ADDRESS    namespace NS (made by the caller) on it: its eth0 is
#                                      the peer of VETH (a port of br0), ADDRESS/24, multicast
#
# The bridge floods multicast to every port (snooping off): every host hears every
# group, as on a hub, without IGMP.
bridge_hub() {
  ip -n "$1" link add br0 type bridge
  ip -n "$1" link set br0 type bridge mcast_snooping 0
  ip -n "$1" link set br0 up
}

bridge_host() {
  local hub="$1" ns="$2" veth="$3" address="$4"
  ip link add "$veth" type veth peer name eth0 netns "$ns"
  ip link set "$veth" netns "$hub" up
  ip -n "$hub" link set "$veth" master br0 up
  ip -n "$ns" link set lo up
  ip -n "$ns" addr add "$address/24" dev eth0
  ip -n "$ns" link set eth0 up multicast on
  ip -n "$ns" route add 224.0.0.0/4 dev eth0
}
