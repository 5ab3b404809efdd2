"""A node lost mid-run (slow: a two-node Ray cluster on this machine, ~40 s to start on 2
cores): the actor on the lost node is restarted by Ray on the node left, once that node
has room, and its trial rerun; every trial once, the rerun said.
Run with ``python -m pytest -m slow tests/client/bench/test_ray_cluster.py``."""

from __future__ import annotations

from collections.abc import Iterator

import pytest
import ray
from ray.cluster_utils import Cluster

from galton.analysis.board import BoardSpec
from galton.client.bench.executor import Retry, TrialHooks
from galton.client.bench.experiment import ExperimentConfig, run_plan
from galton.client.bench.ray_executor import RaySettings, ray_executor
from galton.client.bench.trial import TrialConfig

pytestmark = pytest.mark.slow

TIMEOUT_S = 60.0


@pytest.fixture(scope="module")
def cluster() -> Iterator[Cluster]:
    """A head node and a worker node of one CPU each; this process its driver."""
    started = Cluster(initialize_head=True, head_node_args={"num_cpus": 1,
                                                            "include_dashboard": False})
    try:
        started.add_node(num_cpus=1)
        started.wait_for_nodes()
        ray.init(address=started.address, log_to_driver=False)
        yield started
    finally:
        ray.shutdown()
        started.shutdown()


def test_an_actor_on_a_lost_node_is_restarted_and_its_trial_rerun(cluster: Cluster) -> None:
    config = ExperimentConfig(board=BoardSpec.load("small"), engines=("mujoco",),
                              balls=(10,), repetitions=4, max_sim_time=20.0)
    worker = cluster.list_all_nodes()[1]
    retries: list[Retry] = []
    with ray_executor(RaySettings("auto", actors=2), "mujoco", TIMEOUT_S, 2) as executor:
        assert executor.describe()["nodes"] == 2
        on_worker = next(name for name, facts in executor.facts.items()
                         if facts.node == worker.node_id)

        def lose_the_node(name: str, trial: TrialConfig) -> None:
            """The worker node's actor has its first trial: the node goes."""
            if name == on_worker and worker in cluster.list_all_nodes():
                cluster.remove_node(worker, allow_graceful=False)
        results = run_plan(executor, config, TrialHooks(on_start=lose_the_node,
                                                        on_retry=retries.append))
    assert [t.repetition for t in results.trials] == [0, 1, 2, 3]
    assert all(t.settled == t.balls for t in results.trials)
    assert [r.worker for r in retries] == [on_worker]
    assert results.executor["retried"] == [r.to_dict() for r in retries]
