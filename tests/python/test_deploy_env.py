"""The environment that docker/compose.yaml and deploy/k8s/rdmeshd.yaml give rdmeshd is one it
starts and serves with: every RDMESH_* variable is one of its flags' (`rdmeshd --help` names each
flag's variable), and every value parses (sizes such as 256MiB, log formats). Neither file is run
here (no container engine): this keeps them from drifting away from the daemon's flags."""

import pathlib
import re
import subprocess

import pytest
import yaml

from conftest import CUBE, RDMESHD

ROOT = pathlib.Path(__file__).resolve().parents[2]


def _compose_environment():
    compose = yaml.safe_load((ROOT / "docker" / "compose.yaml").read_text())
    replicas = [s for name, s in compose["services"].items() if name.startswith("rdmeshd")]
    assert len(replicas) == 3
    assert all(s["environment"] == replicas[0]["environment"] for s in replicas)
    return {key: str(value) for key, value in replicas[0]["environment"].items()}


def _kubernetes_environment():
    deployment = next(d for d in yaml.safe_load_all((ROOT / "deploy" / "k8s" /
                                                     "rdmeshd.yaml").read_text())
                      if d and d.get("kind") in ("Deployment", "StatefulSet"))
    container = next(c for c in deployment["spec"]["template"]["spec"]["containers"]
                     if c["name"] == "rdmeshd")
    return {item["name"]: str(item["value"]) for item in container["env"] if "value" in item}


@pytest.mark.parametrize("environment", [_compose_environment, _kubernetes_environment],
                         ids=["compose", "kubernetes"])
def test_deployment_environment_starts_and_serves(start_daemon, tmp_path, environment):
    env = environment()
    assert env, "no RDMESH_* variables found"
    flags = set(re.findall(r"Env:(RDMESH_\w+)", subprocess.run(
        [RDMESHD, "--help"], capture_output=True, text=True, check=True).stdout))
    assert set(env) <= flags, "not an rdmeshd flag: %s" % sorted(set(env) - flags)
    # The container's paths become this test's; the test's own --listen wins over RDMESH_LISTEN.
    for key in ("RDMESH_DATA_ROOT", "RDMESH_CACHE_DIR", "RDMESH_SPOOL_DIR"):
        if key in env:
            env[key] = str(tmp_path / key.lower())
            pathlib.Path(env[key]).mkdir()
    daemon = start_daemon(env=env)
    result = daemon.client().mesh(CUBE)
    assert result.summary.faces_ok == 9 and result.summary.faces_failed == 0
    if "RDMESH_CACHE_DIR" in env:  # both files turn the shared parsed-model store on
        assert list(pathlib.Path(env["RDMESH_CACHE_DIR"]).glob("*.rdm"))
