"""The install's extras hold: a client without the ``[daemon]`` and ``[bench]`` extras drives
a daemon (SDK and CLI), a workstation without engines runs the benchmark against a remote
daemon, and nothing imports Ray (``[cluster]``) unless ``--ray`` is given. The client runs
in a subprocess in which importing a left-out package fails, as it would where that
package is not installed; the daemon it drives is a real one."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
import tomllib
from pathlib import Path

import pytest

from galton.client import EmbeddedDaemon
from galton.client.sdk.embedded import free_loopback_port

ROOT = Path(__file__).resolve().parents[1]
ENGINES = ("mujoco", "pybullet", "pybullet_data", "pybullet_utils", "dartpy")
BENCH_ONLY = ("matplotlib", "scipy")
DAEMON_ONLY = ("psutil",)
CLUSTER_ONLY = ("ray",)
BLOCKER = textwrap.dedent('''
    import importlib.abc, os, sys

    class Blocker(importlib.abc.MetaPathFinder):
        """Import of a left-out package fails, as where it is not installed."""
        blocked = set(os.environ["GALTON_TEST_BLOCKED"].split(","))

        def find_spec(self, name, path=None, target=None):
            if name.split(".")[0] in self.blocked:
                raise ModuleNotFoundError(f"No module named {name!r} (left out)", name=name)
            return None

    sys.meta_path.insert(0, Blocker())
''')
SDK_SCRIPT = textwrap.dedent('''
    import sys
    from galton.client import Client, plane, spheres
    with Client(sys.argv[1], sys.argv[2], timeout=20) as sim:
        sim.load_world(sys.argv[3])
        sim.spawn(plane(), spheres(["ball"], [[0, 0, 1]], radius=0.05))
        sim.step(100)
        print("z", sim.get_states(["ball"]).positions[0, 2])
    loaded = sorted(m for m in sys.modules if m.split(".")[0] in sys.argv[4].split(","))
    print("loaded", loaded)
''')


def run_without(blocked: tuple[str, ...], args: list[str], tmp_path: Path,
                timeout: float = 120) -> subprocess.CompletedProcess[str]:
    """Run a command in a Python where the ``blocked`` packages cannot be imported."""
    (tmp_path / "sitecustomize.py").write_text(BLOCKER)
    env = {**os.environ, "PYTHONPATH": str(tmp_path), "GALTON_TEST_BLOCKED": ",".join(blocked)}
    return subprocess.run(args, capture_output=True, text=True, env=env, cwd=tmp_path,
                          timeout=timeout, check=False)


def console_command(name: str) -> str:
    return str(Path(sys.executable).parent / name)


def test_the_blocker_blocks(tmp_path: Path) -> None:
    done = run_without(("scipy",), [sys.executable, "-c", "import scipy"], tmp_path)
    assert done.returncode != 0 and "left out" in done.stderr


def test_the_base_install_names_no_engine_and_no_plotting() -> None:
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    base = " ".join(project["dependencies"])
    for left_out in ("mujoco", "pybullet", "dartpy", "matplotlib", "scipy", "psutil", "ray"):
        assert left_out not in base
    extras = project["optional-dependencies"]
    assert {"mujoco", "pybullet", "psutil"} <= {d.split(">")[0] for d in extras["daemon"]}
    assert {"scipy", "matplotlib"} <= {d.split(">")[0] for d in extras["bench"]}
    assert "matplotlib" not in " ".join(extras["daemon"])
    assert extras["all"] == ["galton-bridge[daemon,bench,ode,dart,view]"]
    assert {"yourdfpy"} <= {d.split(">")[0] for d in extras["ode"]}
    assert extras["dart"] == ["dartpy>=6.20"]
    assert {d.split(">")[0] for d in extras["cluster"]} == {"ray[client]"}
    assert "cluster" in extras["test"][0] and "ray" not in " ".join(extras["all"])


@pytest.mark.parametrize("engine", ["pybullet"])
def test_a_client_only_install_drives_a_daemon(daemon: EmbeddedDaemon, tmp_path: Path) -> None:
    blocked = ENGINES + BENCH_ONLY + DAEMON_ONLY + CLUSTER_ONLY
    target = ["--connect", daemon.endpoint, "--instance", daemon.instance]
    status = run_without(blocked, [console_command("galton-client"), *target, "status",
                                   "--json"], tmp_path)
    assert status.returncode == 0, status.stderr
    assert f'"engine": "{daemon.engine}"' in status.stdout
    sdk = run_without(blocked, [sys.executable, "-c", SDK_SCRIPT, daemon.instance,
                                daemon.endpoint, daemon.engine, ",".join(blocked)], tmp_path)
    assert sdk.returncode == 0, sdk.stderr
    assert "loaded []" in sdk.stdout
    assert float(sdk.stdout.split("z ")[1].split()[0]) < 1.0  # the ball fell


@pytest.mark.parametrize("engine", ["mujoco"])
def test_a_workstation_without_engines_runs_the_bench_remotely(
        daemon: EmbeddedDaemon, tmp_path: Path) -> None:
    out = tmp_path / "results"
    done = run_without(ENGINES + DAEMON_ONLY + CLUSTER_ONLY, [
        console_command("galton-client"), "bench", "--connect", daemon.endpoint,
        "--instances", daemon.instance, "--engines", daemon.engine, "--board", "small",
        "--balls", "5", "--repetitions", "1", "--out", str(out), "--json"], tmp_path,
        timeout=240)
    assert done.returncode == 0, done.stderr
    assert (out / "results.json").is_file() and (out / "report.md").is_file()


def test_ray_is_asked_for_only_with_ray(tmp_path: Path) -> None:
    """Without the [cluster] extra, --ray says which extra to install (and no daemon or
    trial starts); the runs above imported no Ray."""
    done = run_without(CLUSTER_ONLY, [
        console_command("galton-client"), "bench", "--ray", "local", "--engines", "mujoco",
        "--board", "small", "--balls", "5", "--repetitions", "1", "--out",
        str(tmp_path / "results")], tmp_path)
    assert done.returncode == 1, done.stderr
    assert "--ray needs the [cluster] extra: pip install 'galton-bridge[cluster]'" in (
        done.stderr)
    assert not (tmp_path / "results" / "results.json").exists()


def test_the_daemon_runs_without_plotting(tmp_path: Path) -> None:
    """galton-daemon on a robot: no matplotlib, no scipy."""
    (tmp_path / "sitecustomize.py").write_text(BLOCKER)
    env = {**os.environ, "PYTHONPATH": str(tmp_path),
           "GALTON_TEST_BLOCKED": ",".join(BENCH_ONLY)}
    endpoint = f"tcp/127.0.0.1:{free_loopback_port()}"
    with subprocess.Popen([console_command("galton-daemon"), "--engine", "mujoco",
                           "--instance", "footprint", "--listen", endpoint],
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                          env=env, cwd=tmp_path) as daemon:
        try:
            assert daemon.stdout is not None
            first = daemon.stdout.readline()  # the readiness line, or why it failed
            assert "galton-daemon ready" in first, first + daemon.stdout.read()
            done = run_without((), [console_command("galton-client"), "--connect", endpoint,
                                    "--instance", "footprint", "status", "--json"], tmp_path)
            assert done.returncode == 0, done.stderr
            assert '"engine": "mujoco"' in done.stdout
        finally:
            daemon.terminate()
