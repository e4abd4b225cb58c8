"""The CLI runs each command in a child process (clients/cli/isolation.h): when the child dies by
a signal, the parent exits with the documented code and message. A FIFO as the model keeps the
child in the loading phase until the test has signalled it. `rdmesh` is a launcher that starts
rdmesh-local as that child; rdmesh-local run by hand forks a child of its own."""

import json
import os
import pathlib
import shutil
import signal
import subprocess
import time

import pytest


def stat_fields(stat):
    """The fields of a /proc/PID/stat file after the command name: state, parent pid, ..."""
    return stat.read_text().rsplit(")", 1)[1].split()


def children(pid):
    """Pids of the live processes whose parent is `pid`."""
    found = []
    for stat in pathlib.Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat_fields(stat)
        except OSError:
            continue
        if int(fields[1]) == pid and fields[0] != "Z":
            found.append(int(stat.parent.name))
    return found


def waits_in_open(pid):
    """Whether `pid` sleeps in open(2) on a FIFO that has no writer yet."""
    proc = pathlib.Path("/proc/%d" % pid)
    try:
        state = stat_fields(proc / "stat")[0]
        wchan = (proc / "wchan").read_text().strip()
        if wchan == "0":  # a kernel that hides wait channels: the system call's number, x86-64
            return state == "S" and (proc / "syscall").read_text().split()[0] in ("2", "257")
    except (OSError, IndexError):
        return False
    return state == "S" and wchan == "wait_for_partner"


@pytest.fixture
def stuck_run(cli, tmp_path):
    """Starts `rdmesh ARGS` on a FIFO model (the run waits in loading); yields a function
    start(*args, env=None, program=cli) -> (process, child pid)."""
    fifo = tmp_path / "model.step"
    os.mkfifo(fifo)
    started = []

    def start(*args, env=None, program=cli):
        process = subprocess.Popen([str(program), *args[:1], str(fifo), *args[1:]],
                                   stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                   env=dict(os.environ, **(env or {})))
        started.append(process)
        deadline = time.monotonic() + 10
        while not children(process.pid):
            assert time.monotonic() < deadline, "rdmesh started no child process"
            time.sleep(0.02)
        [child] = children(process.pid)
        # A signal that comes before the child reaches open(2) ends it through the cancelled
        # Context, which is another path than the one the tests mean to take.
        while not waits_in_open(child):
            assert time.monotonic() < deadline, "the child never waited in open(2) on the model"
            time.sleep(0.02)
        return process, child

    yield start
    for process in started:
        if process.poll() is None:
            process.kill()
            process.wait()


def finish(process):
    stdout, stderr = process.communicate(timeout=30)
    lines = [line for line in stdout.splitlines() if line.strip()]
    return process.returncode, json.loads(lines[-1]) if lines else None, stderr


@pytest.mark.parametrize("program", ["rdmesh", "rdmesh-local"])
@pytest.mark.parametrize("command", [["info"], ["mesh", "-o", "out.msh"]])
def test_reader_crash_exits_3(cli, stuck_run, command, program):
    process, child = stuck_run(*command, "--json", program=cli.parent / program)
    os.kill(child, signal.SIGSEGV)
    code, error, stderr = finish(process)
    message = "cannot read '%s': the STEP reader crashed (SIGSEGV) on this model"
    assert code == 3, stderr
    assert "rdmesh: error: " + message % process.args[2] in stderr
    assert error["exit_code"] == 3
    assert error["error"]["code"] == "parse_error"
    assert error["error"]["message"] == message % process.args[2]


def test_killed_reader_is_named(stuck_run):
    process, child = stuck_run("info")
    os.kill(child, signal.SIGKILL)
    code, _, stderr = finish(process)
    assert code == 3
    assert "the STEP reader was killed (SIGKILL) on this model" in stderr


def test_sigterm_is_passed_on_and_exits_4(stuck_run):
    process, child = stuck_run("mesh", "-o", "out.msh", "--json")
    process.send_signal(signal.SIGTERM)
    code, error, stderr = finish(process)
    assert code == 4, stderr
    assert "interrupted while loading" in stderr and "(SIGTERM)" in stderr
    assert error["exit_code"] == 4 and error["error"]["code"] == "cancelled"
    assert not pathlib.Path("/proc/%d" % child).exists()  # ended and reaped


def test_second_interrupt_kills_a_stuck_run(stuck_run):
    # The child waits in open(2), which a cancelled Context cannot end: the second SIGINT does.
    process, _ = stuck_run("info")
    process.send_signal(signal.SIGINT)
    time.sleep(0.3)
    assert process.poll() is None
    process.send_signal(signal.SIGINT)
    code, _, stderr = finish(process)
    assert code == 4
    assert "interrupted while loading" in stderr and "(SIGKILL)" in stderr


def test_no_fork_runs_in_one_process(cli, tmp_path):
    fifo = tmp_path / "model.step"
    os.mkfifo(fifo)
    process = subprocess.Popen([str(cli), "info", str(fifo)], stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True,
                               env=dict(os.environ, RDMESH_NO_FORK="1"))
    try:
        time.sleep(0.5)
        assert process.poll() is None and children(process.pid) == []
    finally:
        process.kill()
        process.wait()
    assert process.returncode == -signal.SIGKILL


def test_the_launcher_loads_only_the_c_library(cli):
    # Its start-up is paid on every run: no C++ library, no allocator, no OCCT.
    dynamic = subprocess.run(["readelf", "-d", str(cli)], capture_output=True, text=True,
                             check=True).stdout
    needed = [line.split("[")[1].rstrip("]") for line in dynamic.splitlines()
              if "(NEEDED)" in line]
    assert needed == ["libc.so.6"]


def test_the_launcher_runs_the_child_and_passes_its_exit_code(cli, data_dir, tmp_path):
    # A bad option: rdmesh-local's own usage error and code come back through the launcher.
    run = subprocess.run([str(cli), "mesh", str(tmp_path / "none.step"), "-o", "x.msh",
                          "--no-such-flag"],
                         capture_output=True, text=True)
    assert run.returncode == 2 and "--no-such-flag" in run.stderr
    run = subprocess.run([str(cli), "info", str(tmp_path / "none.step"), "--json"],
                         capture_output=True, text=True)
    assert run.returncode == 3 and json.loads(run.stdout)["error"]["code"] == "not_found"


def test_a_launcher_without_rdmesh_local_says_so(cli, tmp_path):
    alone = tmp_path / "rdmesh"
    shutil.copy2(cli, alone)
    for command in (["info", "x.step"], ["--help"]):
        run = subprocess.run([str(alone), *command], capture_output=True, text=True)
        assert run.returncode == 2
        assert str(tmp_path / "rdmesh-local") in run.stderr
