"""What the models learn: RND's novelty fades on what it sees; the forward model fits dynamics."""

from __future__ import annotations

import torch
from devlearn_curiosity import RND, ForwardModel, ForwardModelConfig, RNDConfig

from devlearn.api.learned import Transitions


def states(x: torch.Tensor) -> Transitions:
    """Transitions whose next observation is ``x`` (RND looks at the next observation)."""
    return Transitions({"state": x}, torch.zeros(len(x), 2), {"state": x})


def test_rnd_error_falls_on_repeated_states_and_stays_higher_on_new_ones():
    torch.manual_seed(0)
    gen = torch.Generator().manual_seed(1)
    seen, new = torch.randn(64, 8, generator=gen), torch.randn(512, 8, generator=gen)
    rnd = RND(RNDConfig(mini_batches=1), {"state": (8,)}, 2)
    rnd.observe(states(seen))
    with torch.no_grad():
        before_seen = rnd.compute_reward(states(seen)).mean()
        before_new = rnd.compute_reward(states(new)).mean()
    assert before_seen > 0.5 * before_new  # untrained: no preference for the repeated states
    for _ in range(150):
        rnd.update(states(seen), env_steps=0)
    with torch.no_grad():
        after_seen = rnd.compute_reward(states(seen)).mean()
        after_new = rnd.compute_reward(states(new)).mean()
    assert after_seen < 0.15 * before_seen  # measured 0.06
    assert after_new > 1.5 * after_seen  # measured 2.1x


def test_forward_model_learns_a_linear_system():
    torch.manual_seed(0)
    gen = torch.Generator().manual_seed(1)
    a_matrix = torch.linalg.qr(torch.randn(4, 4, generator=gen))[0] * 0.9
    b_matrix = torch.randn(4, 2, generator=gen) * 0.5

    def batch(n: int) -> Transitions:
        x = torch.randn(n, 4, generator=gen)
        u = torch.rand(n, 2, generator=gen) * 2 - 1
        return Transitions({"state": x}, u, {"state": x @ a_matrix.T + u @ b_matrix.T})

    model = ForwardModel(ForwardModelConfig(), {"state": (4,)}, 2)
    held_out = batch(512)
    model.observe(held_out)
    with torch.no_grad():
        before = model.compute_reward(held_out).mean()
    for _ in range(100):
        model.update(batch(256), env_steps=0)
    with torch.no_grad():
        after = model.compute_reward(held_out)
    assert after.mean() < 0.02 * before  # measured 0.001
    # It learned the dynamics, not the data: a transition that breaks them is surprising.
    wrong = Transitions(held_out.observations, -held_out.actions, held_out.next_observations)
    with torch.no_grad():
        assert model.compute_reward(wrong).mean() > 10 * after.mean()  # measured 94x
