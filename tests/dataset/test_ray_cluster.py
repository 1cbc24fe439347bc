"""A simulated 2-node Ray cluster (ray.cluster_utils.Cluster: two raylets on this machine, loopback) runs
a job; batch(ray=ADDRESS) joins it as `warprt batch --ray ADDRESS` does."""

import numpy as np

import warprt
from marks import slow
from warprt.dataset import batch
from warprt.image import read_image

from dataset.jobs import SCENE, require_ray, write_job


@slow
def test_two_node_cluster_runs_a_job(tmp_path):
    ray = require_ray()
    from ray.cluster_utils import Cluster

    if ray.is_initialized():
        ray.shutdown()
    # Each node: 1 CPU (one actor each), a small object store, no autoscaler monitor and no log monitor
    # (nothing is forwarded to the driver anyway): about 3 s less to start on 2 cores.
    args = {"num_cpus": 1, "object_store_memory": 96 * 2**20, "no_monitor": True, "include_log_monitor": False}
    cluster = Cluster(initialize_head=True, head_node_args={**args, "include_dashboard": False})
    try:
        cluster.add_node(**args)
        cluster.wait_for_nodes()
        job = write_job(tmp_path, 'scene = "{scene}"\noutput = "f/{frame}.npz"\n[orbit]\nframes = 6\n')
        rows = batch(job, tmp_path / "out", ray=cluster.address).rows
        assert [r["frame"] for r in rows] == list(range(6))
        assert len({r["worker"]["node"] for r in rows}) == 2  # one actor on each node
        assert not ray.is_initialized()  # batch joined the cluster, so it left it
        for r in rows:
            image, _ = warprt.render(warprt.load_scene(SCENE, overrides=r["overrides"]))
            assert np.array_equal(read_image(tmp_path / "out" / r["outputs"]["color"]), image)
    finally:
        cluster.shutdown()
