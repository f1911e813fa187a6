# SPDX-License-Identifier: Apache-2.0
# Sourced by tools/run_team.sh (--hosts --loss P) and tools/loss_check.sh: the one
# packet-loss rule, so that the check measures the rule the team runs under.
#
#   install_loss_rule NAMESPACE OWN_IP PERCENT [EXEMPT_IP...]
#
# Drops PERCENT % (one decimal) of the namespace's incoming IPv4 UDP packets. In a
# prerouting chain at priority -450, before defragmentation (-400) and conntrack
# (-200): each IP fragment is a packet of its own, lost independently, as on a lossy
# link; every fragment has `ip protocol udp` in its header (the UDP header is in the
# first one only). The host's own multicast, looped back to it (source OWN_IP), is not
# incoming. Nor are packets from EXEMPT_IP (run_team.sh's default loss scope: a
# robot's SENSOR frames come from its own drivers, which the simulator stands in
# for, not over the radio). Two counters in table inet elaslam_loss: every incoming
# UDP packet ("incoming"), and those dropped ("dropped").
install_loss_rule() {
  local ns="$1" ip="$2" permille
  permille=$(awk -v p="$3" 'BEGIN { printf "%d", p * 10 + 0.5 }')
  shift 3
  [ "$#" -eq 0 ] || ip="{ $ip$(printf ', %s' "$@") }"
  ip netns exec "$ns" nft -f - <<RULE
table inet elaslam_loss {
  chain pre {
    type filter hook prerouting priority -450; policy accept;
    ip protocol udp ip saddr != $ip counter comment "incoming"
    ip protocol udp ip saddr != $ip numgen random mod 1000 < $permille counter drop comment "dropped"
  }
}
RULE
}
