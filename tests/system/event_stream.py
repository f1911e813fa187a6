# SPDX-License-Identifier: Apache-2.0
"""The viewer's event stream (/events, Server-Sent Events) read as a browser reads it,
for viewer_attacks.py and viewer_clients.py. Standard library only."""
import socket


def state_counts(s, going, timeout):
    """Reads the open stream on socket `s` while going() and the viewer keeps it open,
    each read waiting at most `timeout` s: yields the number of state events in each
    chunk read."""
    s.settimeout(timeout)
    while going():
        try:
            chunk = s.recv(65536)
        except socket.timeout:
            continue
        if not chunk:
            break
        yield chunk.count(b"event: state")
