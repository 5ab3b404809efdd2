"""``--ray ADDRESS`` and its options, shared by ``bench``, ``sweep`` and ``report-card``.

Ray (the ``[cluster]`` extra) is imported only when ``--ray`` is given: a client without it
has every other command.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from typing import TYPE_CHECKING, Annotated, Any

import typer

from galton.protocol import InvalidArgumentError

if TYPE_CHECKING:
    from galton.client.bench.ray_executor import RayExecutor
    from galton.client.sdk.client import Client
    from galton.client.sdk.values import Prediction

RayOpt = Annotated[str | None, typer.Option(
    "--ray", metavar="ADDRESS",
    help="Run the trials on Ray: 'local' starts a Ray instance here for the run; 'auto' or "
         "ray://HOST:PORT joins a cluster. Each actor hosts a daemon of its own; a dead "
         "one is restarted by Ray and its trial rerun (the [cluster] extra).")]
RayCpusOpt = Annotated[float, typer.Option(
    "--ray-cpus-per-daemon", min=0.01,
    help="CPUs each Ray actor (one daemon) reserves; a MuJoCo crowd needs 2.")]
RayActorsOpt = Annotated[int | None, typer.Option(
    "--ray-actors", min=1,
    help="Ray actors (daemons) to start (default: as many as the cluster's CPUs hold).")]


def refuse_with_ray(ray: str | None, **others: object) -> None:
    """``--ray`` starts daemons of its own on the cluster's nodes: refuse the options that
    name daemons already running (exit 2)."""
    named = [name for name, value in others.items() if value]
    if ray is not None and named:
        raise typer.BadParameter(
            f"--ray runs on daemons of its own on the cluster's nodes; leave out "
            f"{', '.join(named)}")


def require_ray() -> None:
    """Ray is importable, or a clear error naming the extra that brings it."""
    try:
        import ray  # noqa: F401
    except ImportError as error:
        raise InvalidArgumentError(
            "--ray needs the [cluster] extra: pip install 'galton-bridge[cluster]'") from error


@contextmanager
def ray_run(address: str, cpus_per_daemon: float, actors: int | None, engine: str,
            timeout: float, most: int) -> Iterator[RayExecutor]:
    """A RayExecutor on the cluster at ``address`` (its actors' daemons started with
    ``engine``; at most ``most`` actors unless ``actors`` says), stopped on exit."""
    require_ray()
    from galton.client.bench.ray_executor import RaySettings, ray_executor
    settings = RaySettings(address, cpus_per_daemon, actors)
    with ray_executor(settings, engine, timeout, most) as executor:
        yield executor


def ray_predict(sim: Client, slot: str | None, address: str, cpus_per_daemon: float,
                actors: int | None, timeout: float, horizon: float, futures: int,
                **predict_args: Any) -> tuple[Prediction, dict[str, Any]]:
    """``predict``'s futures over Ray actors, each restoring the world's snapshot (or slot
    ``slot``'s) once: the ensemble, and where it ran (``executor``, with the retried
    batches)."""
    require_ray()
    from galton.client.bench.futures import predict_ensemble, start_of
    from galton.client.bench.ray_executor import RaySettings
    from galton.client.bench.ray_futures import ray_futures
    start = start_of(sim, slot)
    settings = RaySettings(address, cpus_per_daemon, actors)
    with ray_futures(settings, start.engine, timeout, futures) as runner:
        found = predict_ensemble(runner, start, horizon, futures, **predict_args)
        where = runner.executor.describe()
        where["retried"] = [r.to_dict() for r in runner.retried]
    return found, where
