"""DevVecEnv: rsl-rl's VecEnv contract, seeding, worker processes and their failure modes."""

from __future__ import annotations

import functools
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import torch
from rsl_rl.env import VecEnv

from devlearn.env import DevVecEnv, EnvWorkerError
from devlearn.testing.fake_infant import TinyBehavior, TinyConfig, fake_infant_factory

factory = functools.partial(fake_infant_factory, episode_steps=5)


def make(num_envs=3, workers=0, seed=0, eyes=True, infant_factory=factory, **kw) -> DevVecEnv:
    behavior = TinyBehavior(TinyConfig(use_eyes=eyes))
    return DevVecEnv(behavior, num_envs, seed, workers, infant_factory=infant_factory, **kw)


def test_vec_env_contract():
    env = make()
    try:
        assert isinstance(env, VecEnv)
        assert (env.num_envs, env.num_actions, env.max_episode_length) == (3, 3, 5)
        assert env.step_dt == 0.005 and env.unwrapped is env
        obs = env.get_observations()
        assert obs.batch_size == torch.Size([3])
        assert obs["proprioception"].shape == (3, 3)
        assert obs["proprioception"].dtype == torch.float32
        assert obs["eyes"].shape == (3, 2, 8, 8, 3) and obs["eyes"].dtype == torch.uint8
        for t in range(5):
            obs, rewards, dones, extras = env.step(torch.ones(3, 3))
            assert rewards.shape == (3,) and dones.shape == (3,)
            last = t == 4
            assert dones.tolist() == [int(last)] * 3
            assert extras["time_outs"].tolist() == [last] * 3
            assert env.episode_length_buf.tolist() == ([0] * 3 if last else [t + 1] * 3)
            if last:
                assert set(extras["log"]) == {"reward/reach", "reward/counter", "metrics/close"}
                assert len(extras["episode_infos"]) == 3
            else:
                assert extras["log"] == {} and extras["episode_infos"] == []
        # finished envs reset themselves (fixed pose: back to zeros)
        assert torch.all(obs["proprioception"] == 0)
    finally:
        env.close()


def test_returned_observations_are_copies():
    env = make(eyes=False)
    try:
        first = env.get_observations()
        env.step(torch.ones(3, 3))
        assert torch.all(first["proprioception"] == 0)  # not overwritten by the step
    finally:
        env.close()


def test_env_seeds_are_distinct_and_rank_offset():
    rank0 = make(num_envs=4, eyes=False)
    rank1 = make(num_envs=2, eyes=False, rank=1)
    try:
        for env in (rank0, rank1):
            env.set_stage({"random_pose": True})
            env.load_state_dict(env.state_dict())  # restarts episodes with random poses
        p0 = rank0.get_observations()["proprioception"]
        p1 = rank1.get_observations()["proprioception"]
        assert len({tuple(row.tolist()) for row in p0}) == 4
        # rank 1, env i is seeded seed + 1 * num_envs + i: here 2 and 3, like rank 0's envs 2, 3
        torch.testing.assert_close(p1, p0[2:])
    finally:
        rank0.close()
        rank1.close()


def run_script(env: DevVecEnv, steps: int = 12) -> list:
    torch.manual_seed(0)
    out = [env.get_observations()]
    env.set_stage({"random_pose": True})
    for _ in range(steps):
        obs, rewards, dones, extras = env.step(torch.rand(env.num_envs, env.num_actions) * 2 - 1)
        out += [obs, rewards, dones, extras["time_outs"], extras["log"]]
    state = env.state_dict()
    env.load_state_dict(state)
    out.append(env.get_observations())
    return out + [state["envs"][i]["terms"]["counter"] for i in range(env.num_envs)]


def test_workers_match_in_process():
    local, pooled = make(num_envs=3, workers=0), make(num_envs=3, workers=2)
    try:
        assert pooled.observation_shapes == local.observation_shapes
        expected, got = run_script(local), run_script(pooled)
        assert len(expected) == len(got)
        for a, b in zip(expected, got):
            if isinstance(a, dict):
                assert a == pytest.approx(b)
            else:
                torch.testing.assert_close(b, a)
    finally:
        local.close()
        pooled.close()
    names = [b.name for b in pooled._buffers.blocks]
    assert all(not Path("/dev/shm", n).exists() for n in names)


def test_worker_error_is_reraised_with_traceback():
    broken = functools.partial(fake_infant_factory, episode_steps=5, fail_after=2)
    env = make(num_envs=2, workers=1, eyes=False, infant_factory=broken)
    try:
        with pytest.raises(EnvWorkerError) as info:
            for _ in range(3):
                env.step(torch.zeros(2, 3))
        message = str(info.value)
        assert "RuntimeError: fake infant broke on purpose" in message
        assert "fake_infant.py" in message  # the worker's traceback, not just the type
    finally:
        env.close()


PARENT = """
import functools, sys, time
sys.path.insert(0, {env_dir!r})
from devlearn.testing.fake_infant import TinyBehavior, fake_infant_factory
if __name__ == "__main__":  # workers re-import this file: keep their imports light
    from devlearn.env.vec_env import DevVecEnv
    env = DevVecEnv(TinyBehavior(), 2, 0, workers=2,
                    infant_factory=functools.partial(fake_infant_factory, episode_steps=5))
    print(" ".join(str(p.pid) for p in env._pool.procs), flush=True)
    time.sleep(60)
"""


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    status = Path(f"/proc/{pid}/status")
    return status.exists() and "zombie" not in status.read_text()


def test_workers_die_with_parent(tmp_path):
    script = tmp_path / "parent.py"
    script.write_text(PARENT.format(env_dir=str(Path(__file__).parent)))
    parent = subprocess.Popen(
        [sys.executable, str(script)], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True
    )
    try:
        pids = [int(p) for p in parent.stdout.readline().split()]
        assert len(pids) == 2 and all(_alive(p) for p in pids)
        parent.send_signal(signal.SIGKILL)
        parent.wait(timeout=10)
        deadline = time.time() + 10
        while any(_alive(p) for p in pids) and time.time() < deadline:
            time.sleep(0.1)
        assert not any(_alive(p) for p in pids)
    finally:
        parent.kill()
