#!/usr/bin/python3
"""What ReturnFields.edges (or another optional field, --field) costs on the wire: the Mesh
stream's bytes and wall time without and with it, against a running rdmeshd.

    bench/service/edges_stream.py --address 127.0.0.1:50051 MODEL.step [--runs 2]
    bench/service/edges_stream.py --field triangle_deviation MODEL.step
"""

import argparse
import os
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "clients",
                                "python"))
from rdmesh import Client  # noqa: E402


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("model")
    parser.add_argument("--address", default=os.environ.get("RDMESH_ADDRESS", "127.0.0.1:50051"))
    parser.add_argument("--runs", type=int, default=2)
    parser.add_argument("--field", choices=("edges", "triangle_deviation"), default="edges")
    args = parser.parse_args()
    with Client(args.address) as client:
        info = client.upload(args.model)
        for _ in range(args.runs):
            for on in (False, True):
                start = time.monotonic()
                total = count = 0
                for event in client.mesh_stream(info, **{args.field: on}):
                    total += event.ByteSize()
                    count += event.WhichOneof("event") == "edge"
                print("%s=%-5s EdgePolyline events %5d, stream bytes %9d, %.3f s"
                      % (args.field, on, count, total, time.monotonic() - start))


if __name__ == "__main__":
    main()
