"""A run that would be endless or meaningless is refused at once, in one line naming the argument.

dt is MIN_DT (1 microsecond) to MAX_DT (0.1 s), and one call steps at most MAX_STEPS (1e9)
times: `simulate` refuses a ``seconds`` that needs more steps of dt before taking any.
"""

import pytest

import physics
from physics.world import MAX_DT, MAX_STEPS, MIN_DT


def refused(make) -> str:
    with pytest.raises(physics.PhysicsError) as caught:
        make()
    message = str(caught.value)
    assert "\n" not in message
    return message


@pytest.mark.parametrize("dt", [1e-300, 1e-7, 0.11, 1e308, float("inf"), -1 / 240])
def test_a_dt_outside_one_microsecond_to_a_tenth_of_a_second_is_refused_naming_dt(dt):
    message = refused(lambda: physics.World(dt=dt))
    assert message.startswith("dt must be")


@pytest.mark.parametrize("dt", [MIN_DT, 1 / 240, MAX_DT])
def test_a_dt_at_either_end_of_the_range_is_accepted(dt):
    assert physics.World(dt=dt).dt == dt


@pytest.mark.parametrize("seconds", [1e308, 1e9, MAX_STEPS / 240 * 1.001])
def test_seconds_needing_more_than_max_steps_are_refused_naming_seconds_before_any_step(
        seconds):
    world = physics.World()
    world.add_sphere((0, 1, 0))
    message = refused(lambda: physics.simulate(world, seconds))
    assert message.startswith("seconds must be at most") and "1,000,000,000 steps" in message
    assert world.steps == 0


def test_a_step_count_above_max_steps_is_refused_naming_n():
    message = refused(lambda: physics.World().step(MAX_STEPS + 1))
    assert message.startswith("n must be at most")


def test_the_step_limit_scales_with_dt_so_a_longer_dt_allows_longer_runs():
    """The limit is on the steps: seconds refused at dt = 1e-6 pass at dt = 0.1."""
    seconds = 2 * MAX_STEPS * MIN_DT
    refused(lambda: physics.simulate(physics.World(dt=MIN_DT), seconds))
    taken = []                                    # a stand-in step that only counts
    physics.simulate(physics.World(dt=MAX_DT), seconds, record_every=10 ** 6, step=taken.append)
    assert sum(taken) == 20000
