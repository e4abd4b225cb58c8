#!/usr/bin/env python3
"""Measures what routing by model through nginx costs and saves (docs/ROUTING.md), in one run:
three rdmeshd replicas and nginx on loopback, configured as tests/python/test_routing.py does
(deploy/nginx/rdmesh-grpc.conf with local `server` lines).

    /usr/bin/python3 bench/service/routing.py [--models A.step B.step] [--rounds 15] [--rel 1e-3]

Per model:
  - 20 Mesh calls by unknown ids through nginx: the NOT_FOUND round trip that a client's first
    call for a new model costs before it uploads (printed as a line of its own);
  - first call through nginx: Mesh by id (NOT_FOUND), upload, parse, mesh; the parse's
    load_seconds is what a replica that does not hold the model pays;
  - then `--rounds` calls at `--rel` on the cached model, alternating direct to the replica that
    holds it and through nginx: median and 90th percentile wall time of each, and the difference
    (the cost of the nginx hop);
  - then the replica that holds it is killed: the next call through nginx (connection refused,
    the next replica on the ring, NOT_FOUND, upload, parse, mesh) and the one after (cached).
"""

import argparse
import pathlib
import statistics
import sys
import tempfile
import time

import grpc

REPO = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "clients" / "python"))
sys.path.insert(0, str(REPO / "tests" / "python"))
from conftest import Daemon  # noqa: E402
from rdmesh import Client  # noqa: E402
from test_routing import Nginx, _served_by  # noqa: E402

DEFAULT_MODELS = [REPO / "tests" / "data" / "cq_red_cube_blue_cylinder.step",
                  REPO.parent / "shared" / "corpus" / "nist_mbe_pmi_2.stp",
                  REPO.parent / "shared" / "corpus" / "voron_bowden_module.step"]


def timed(call):
    start = time.monotonic()
    result = call()
    return time.monotonic() - start, result


def p90(values):
    return sorted(values)[max(0, int(round(0.9 * len(values))) - 1)]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--models", nargs="+", default=[str(m) for m in DEFAULT_MODELS])
    parser.add_argument("--rounds", type=int, default=15)
    parser.add_argument("--rel", type=float, default=1e-3)
    args = parser.parse_args()

    tmp = pathlib.Path(tempfile.mkdtemp(prefix="routing-bench-"))
    not_found = []
    print("models: %s; %d rounds at max_deviation_rel %g; logs in %s"
          % (", ".join(pathlib.Path(m).name for m in args.models), args.rounds, args.rel, tmp))
    print("| model | parse (load_seconds) | first call via nginx | cached: direct median / p90 "
          "| cached: via nginx median / p90 | nginx hop (median) | after its replica is killed: "
          "first / second call |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    for k, model in enumerate(args.models):
        daemons = [Daemon(tmp / ("replica-%d-%d.log" % (k, i))) for i in range(3)]
        nginx = None
        try:
            for d in daemons:
                d.wait_serving()
            (tmp / ("run-%d" % k)).mkdir()
            nginx = Nginx(tmp / ("run-%d" % k), [d.address for d in daemons])
            routed = Client(nginx.address)
            missing = []
            for i in range(20):
                start = time.monotonic()
                try:
                    for _ in routed.mesh_stream("%064x" % (i + 1)):
                        pass
                except grpc.RpcError as error:
                    assert error.code() == grpc.StatusCode.NOT_FOUND, error
                missing.append(time.monotonic() - start)
            not_found.append("%s: NOT_FOUND round trip through nginx, median %.1f ms, p90 %.1f ms"
                             % (pathlib.Path(model).name, 1000 * statistics.median(missing),
                                1000 * p90(missing)))
            first_seconds, first = timed(lambda: routed.mesh(model, max_deviation_rel=args.rel))
            holder = daemons[_served_by(daemons, first.job_id)]
            # The holder's log line "model <id> '<name>' parsed: N bytes, F faces in S s".
            load = float(holder.log().split("' parsed: ")[1].split(" in ")[1].split(" s")[0])
            direct = holder.client()
            via, straight = [], []
            for _ in range(args.rounds):
                straight.append(timed(lambda: direct.mesh(first.model,
                                                          max_deviation_rel=args.rel))[0])
                seconds, result = timed(lambda: routed.mesh(model, max_deviation_rel=args.rel))
                assert result.model.cached
                via.append(seconds)
            holder.proc.kill()
            holder.proc.wait()
            after_kill, _ = timed(lambda: routed.mesh(model, max_deviation_rel=args.rel))
            second_after, _ = timed(lambda: routed.mesh(model, max_deviation_rel=args.rel))
            routed.close()
            print("| %s | %.3f s | %.3f s | %.3f / %.3f s | %.3f / %.3f s | %+.1f ms "
                  "| %.3f / %.3f s |" % (
                      pathlib.Path(model).name, load, first_seconds,
                      statistics.median(straight), p90(straight), statistics.median(via),
                      p90(via), 1000 * (statistics.median(via) - statistics.median(straight)),
                      after_kill, second_after))
            sys.stdout.flush()
        finally:
            if nginx is not None:
                nginx.stop()
            for d in daemons:
                d.stop()
    print("\n".join(not_found))


if __name__ == "__main__":
    main()
