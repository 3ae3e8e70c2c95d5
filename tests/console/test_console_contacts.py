"""Contacts between robots are detected on every run, on the trusted side: one event per contact episode (not one
per tick), an alert while it lasts, and the episode kept for the run's result. Forced here with the barrier off and
the guard disabled by the trusted-side hook (``ControlLoop(guard=None)``); with the guard on there is none."""
import numpy as np

from swarmdeck.console.runtime.contacts import ContactWatch
from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig
from swarmdeck.devices import ArenaConfig
from swarmdeck.devices.simulated_robots import SimulatedRobots


class Straight:
    """Open loop: every robot full speed along its heading (look-ahead velocities, m/s)."""

    name = "straight ahead"

    def __call__(self, tick):
        th = tick.poses[:, 2]
        return 0.2 * np.column_stack((np.cos(th), np.sin(th))), None


def head_on(**kw):
    poses = np.array([[-0.35, 0.0, 0.0], [0.35, 0.0, np.pi], [0.0, 0.6, 0.0]])
    robots = SimulatedRobots(3, ArenaConfig(), initial_poses=poses)
    loop = ControlLoop(LoopConfig(n_robots=3), source=robots, sink=robots, **kw)
    loop.use_behaviour(Straight())
    loop.set_safety(enabled=False)
    return loop


def test_a_contact_is_one_event_however_long_it_lasts():
    loop = head_on(guard=None)
    frames = [loop.tick() for _ in range(75)]  # they meet, pass through each other (a simulator), part
    events = [e for f in frames for e in f.events if e.startswith("CONTACT:")]
    assert len(events) == 1 and events[0].startswith("CONTACT: robots 0 and 1 touch at t = ")
    touching = [any(a.startswith("robots in contact: 0–1") for a in f.alerts) for f in frames]
    assert sum(touching) > 5 and not touching[-1]  # alerted for the whole episode, then cleared
    (contact,) = loop.contacts.episodes
    assert contact.robots == (0, 1) and contact.distance <= 0.135
    assert loop.contacts.summary() == {"count": 1, "robots": [0, 1], "episodes": [contact.to_dict()]}


def test_with_the_guard_the_same_run_has_no_contact():
    loop = head_on()
    for _ in range(75):
        loop.tick()
    assert loop.contacts.episodes == [] and len(loop.revocations) == 1


def test_touching_again_after_parting_is_a_new_episode():
    watch = ContactWatch()
    ids, seen = np.array([4, 9]), np.array([True, True])
    apart, close = np.array([[0.0, 0.0, 0.0], [0.5, 0.0, 0.0]]), np.array([[0.0, 0.0, 0.0], [0.1, 0.0, 0.0]])
    got = [len(watch.update(k, 0.033 * k, ids, p, seen)) for k, p in enumerate([apart, close, close, apart, close])]
    assert got == [0, 1, 0, 0, 1] and [c.robots for c in watch.episodes] == [(4, 9), (4, 9)]
    assert watch.update(5, 0.2, ids, close, np.array([True, False])) == []  # an unseen robot is not judged
