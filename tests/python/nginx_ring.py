"""nginx's `hash KEY consistent` (ngx_http_upstream_hash_module), reproduced so that tests can
predict where nginx sends a model and docs/ROUTING.md can give the shares and the remapping.

Each upstream `server` line, as written (e.g. "127.0.0.1:50061"), puts 160 points on a ring of
32-bit hashes: crc32(host \\0 port prev) with prev the previous point (little-endian, 0 first).
A request goes to the server of the first point at or after crc32(key), wrapping around; points
of servers that are down or failed are walked past. test_routing.py checks that nginx agrees.

    /usr/bin/python3 tests/python/nginx_ring.py    # shares and remapping for 3 -> 4 replicas
"""

import bisect
import hashlib
import struct
import zlib

POINTS_PER_SERVER = 160  # per unit of weight


class Ring:
    def __init__(self, servers):
        points = []
        for server in servers:
            host, port = server.rsplit(":", 1)
            base = host.encode() + b"\0" + port.encode()
            previous = 0
            for _ in range(POINTS_PER_SERVER):
                previous = zlib.crc32(base + struct.pack("<I", previous))
                points.append((previous, server))
        points.sort()
        self.hashes = [h for h, _ in points]
        self.servers = [s for _, s in points]

    def owner(self, key, dead=()):
        """The server nginx picks for `key` when the servers in `dead` refuse connections."""
        index = bisect.bisect_left(self.hashes, zlib.crc32(key.encode()))
        for step in range(len(self.servers)):
            server = self.servers[(index + step) % len(self.servers)]
            if server not in dead:
                return server
        raise ValueError("every server is down")


def main():
    keys = [hashlib.sha256(b"%d" % i).hexdigest() for i in range(100000)]
    names = ["rdmeshd-%d.rdmeshd:50051" % i for i in range(4)]  # deploy/k8s names
    three, four = Ring(names[:3]), Ring(names)
    before = [three.owner(k) for k in keys]
    after = [four.owner(k) for k in keys]
    for label, owners, servers in (("3 replicas", before, names[:3]), ("4 replicas", after, names)):
        print("%s: share of models per replica %s" % (label, ", ".join(
            "%.1f%%" % (100.0 * owners.count(s) / len(keys)) for s in servers)))
    moved = [(a, b) for a, b in zip(before, after) if a != b]
    to_new = all(b == names[3] for _, b in moved)
    print("3 -> 4 replicas: %.1f%% of the models move (1/4 = 25%%), %s to the new replica" % (
        100.0 * len(moved) / len(keys), "all" if to_new else "not all"))
    dead = [three.owner(k, dead=[names[1]]) for k in keys]
    lost = [(a, b) for a, b in zip(before, dead) if a != b]
    print("3 replicas, %s down: %.1f%% of the models move (its share), the others stay: %s" % (
        names[1], 100.0 * len(lost) / len(keys), all(a == names[1] for a, _ in lost)))


if __name__ == "__main__":
    main()
