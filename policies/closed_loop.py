"""Run one policy episode in closed loop and score it with the evaluator (the paper's protocol).

Control runs at 60 Hz (each control step SUBSTEPS physics steps); the policy is stepped at its own rate
(20 Hz for the learned policies: each action held for three control steps). At each policy step the
runner renders what the policy observes when the policy will be queried within its observation window,
queries it when no action is queued, executes `actions_per_query` rows of the returned chunk, one per
policy step, and stops on stable success (reach-and-stop, with the task's dwell) or at the budget, 1.5x
the expert horizon. The evaluator counts control steps and policy queries, so the record carries
`control_steps_to_stable` and `policy_queries_to_stable`.

A policy that raises or returns a wrong shape ends the episode as an error; the record keeps what was
executed before (steps, stages, violations).
"""

from __future__ import annotations

import logging
import time
from collections import deque
from dataclasses import dataclass, field

import numpy as np

from policies.interface import Policy, PolicyError
from sim import physics
from sim.scene.builder import Scene
from teleop.recorder import EpisodeRecording, episode_horizon, home

log = logging.getLogger(__name__)


@dataclass
class EpisodeTiming:
    """Seconds spent per part of the loop (`b2d bench policy`); `render_cpu` is the rendering thread's
    CPU seconds (with LP_NUM_THREADS=0 Mesa rasterizes on it), which a loaded machine does not inflate."""

    render: float = 0.0
    render_cpu: float = 0.0
    policy: float = 0.0
    physics: float = 0.0
    evaluate: float = 0.0
    queries: int = 0
    control_steps: int = 0

    def as_dict(self) -> dict:
        return dict(self.__dict__)


@dataclass
class EpisodeOutcome:
    record: dict                      # the evaluator's episode record (evaluation.records.EpisodeRecord)
    recording: object                 # the RawRecording (actions and states per control step)
    timing: EpisodeTiming = field(default_factory=EpisodeTiming)


def check_chunk(chunk, action_dim: int, policy_name: str) -> np.ndarray:
    try:
        chunk = np.asarray(chunk, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise PolicyError(f"{policy_name} returned no numeric action chunk ({exc})") from exc
    if chunk.ndim != 2 or chunk.shape[0] < 1 or chunk.shape[1] != action_dim:
        raise PolicyError(f"{policy_name} returned an action chunk of shape {chunk.shape}; expected "
                          f"(rows >= 1, {action_dim}) joint targets")
    if not np.isfinite(chunk).all():
        raise PolicyError(f"{policy_name} returned non-finite actions")
    return chunk


class IncompatiblePolicy(ValueError):
    """The policy was made for another embodiment, or reads what this scene does not have."""


def check_compatible(policy: Policy, scene: Scene) -> None:
    """Refuse, before the first step, a policy made for another embodiment."""
    spec, actions = policy.observation_spec, policy.action_spec
    model = scene.model
    names = tuple(model.actuator(i).name for i in range(model.nu))
    where = f"policy {policy.name} vs setting {scene.task.name} on {scene.layout.embodiment}"
    if actions is not None and tuple(actions.names) != names:
        raise IncompatiblePolicy(f"{where}: the policy commands {actions.dim} actuators {list(actions.names)[:4]}..., "
                         f"the embodiment has {len(names)} {list(names)[:4]}...")
    if spec.state_names and tuple(spec.state_names) != tuple(scene.layout.joint_names):
        raise IncompatiblePolicy(f"{where}: the policy reads {len(spec.state_names)} joints, the embodiment has "
                         f"{len(scene.layout.joint_names)}")
    missing = [v for v in spec.views if v not in {model.camera(i).name for i in range(model.ncam)}]
    if missing:
        raise IncompatiblePolicy(f"{where}: views {missing} are not cameras of the scene")
    if physics.CONTROL_HZ % spec.rate_hz:
        raise IncompatiblePolicy(f"{where}: policy rate {spec.rate_hz} Hz must divide the control rate {physics.CONTROL_HZ} Hz")


def run_episode(policy: Policy, scene: Scene, seed: int, episode_id: str = "0000",
                max_steps: int | None = None, stop_on_success: bool = True) -> EpisodeOutcome:
    from policies.observe import ObservationSource

    check_compatible(policy, scene)
    spec = policy.observation_spec
    stride = physics.CONTROL_HZ // spec.rate_hz
    data = home(scene)
    episode = EpisodeRecording(scene, data)
    timing = EpisodeTiming()
    source = ObservationSource(scene, spec) if not spec.privileged else None
    horizon = episode_horizon(scene, max_steps)
    queue: deque[np.ndarray] = deque()
    termination, error = None, None
    clock = time.perf_counter
    action = None
    try:
        policy.reset(seed, scene.task.instruction)
        step = 0
        while step < horizon:
            tick, queried = step // stride, False
            if step % stride == 0:                   # a policy step: maybe observe, maybe query, next action
                if getattr(policy, "done", None) and policy.done(tick):
                    break
                if source is not None and len(queue) < spec.n_obs_steps:
                    t0, cpu0 = clock(), time.thread_time()
                    source.capture(data)
                    timing.render += clock() - t0
                    timing.render_cpu += time.thread_time() - cpu0
                if not queue:
                    obs = (source.observation(scene.task.instruction, tick) if source is not None
                           else {"sim": (scene, data), "tick": tick, "instruction": scene.task.instruction})
                    t0 = clock()
                    try:
                        chunk = policy.act(obs)
                    except PolicyError:
                        raise
                    except Exception as exc:         # the policy's own fault: this episode ends as an error
                        raise PolicyError(f"{policy.name} raised {type(exc).__name__}: {exc}") from exc
                    timing.policy += clock() - t0
                    chunk = check_chunk(chunk, scene.model.nu, policy.name)
                    queue.extend(chunk[: policy.actions_per_query])
                    queried = True
                    timing.queries += 1
                action = queue.popleft()
            t0 = clock()
            physics.step_control(scene.model, data, action)
            t1 = clock()
            record = episode.step(data, action, getattr(policy, "step_flags", 0), getattr(policy, "step_reasons", ""),
                                  policy_query=queried)
            timing.physics += t1 - t0
            timing.evaluate += clock() - t1
            timing.control_steps += 1
            step += 1
            if stop_on_success and record.stable:
                break                                  # reach-and-stop
    except PolicyError as exc:
        termination, error = "error", str(exc)
        log.warning("episode %s of %s ended in error: %s", episode_id, policy.name, exc)
    finally:
        if source is not None:
            source.close()
    recording = episode.finish(episode_id, seed, policy.name, termination=termination, error=error)
    return EpisodeOutcome(recording.extra["episode_record"], recording, timing)
