"""A policy served elsewhere (pi0.5 or GR00T in their own environments, or `b2d serve`) behind the policy
interface. The URL's scheme picks the protocol: `tcp://host:port` the harness's length-prefixed JSON,
`ws://host:port` openpi's msgpack websocket.

The observation sent is the closed loop's own window, {"images": {view: uint8 [n_obs, H, W, 3]},
"state": float64 [n_obs, J], "tactile": {site: ...}, "tick", "instruction"}, with the instruction as
`prompt` on the websocket (openpi's key). Any fault of the server becomes a `PolicyError` naming the server
and the fault, which ends that episode as an error; the next episode connects again.
"""

from __future__ import annotations

import numpy as np

from policies.interface import PolicyError
from policies.remote import tcp_wire
from policies.remote.layout import Layout, check_layout_fits
from policies.remote.spec import RemoteSpec
from policies.remote.transports import DEFAULT_TIMEOUT_S, RemoteFault, open_transport


class RemotePolicy:
    def __init__(self, url: str, spec: RemoteSpec | None = None, timeout: float = DEFAULT_TIMEOUT_S,
                 max_bytes: int = tcp_wire.DEFAULT_MAX_BYTES, layout: Layout | None = None):
        self.url = url
        self.transport = open_transport(url, timeout, max_bytes)
        if spec is None:                  # ask the server; a server that cannot say needs a declared spec
            try:
                raw = self.transport.spec()
            except RemoteFault as exc:
                raise PolicyError(f"policy server {url}: {exc} (a server that is not b2d's needs a declared "
                                  "spec: --spec FILE)") from exc
            if raw is None:
                raise PolicyError(f"policy server {url} does not describe its policy: declare its spec (--spec FILE)")
            spec = RemoteSpec.from_dict(raw, url)
        self.spec = spec
        self.name = spec.name
        self.observation_spec = spec.observation_spec
        self.action_spec = spec.action_spec
        self.actions_per_query = spec.actions_per_query
        # a fixed-width head: states go out encoded, actions come back in `layout.dim` slots
        if layout is None and spec.layout:
            layout = Layout.from_dict(spec.layout, f"{url} (spec.layout)")
        if layout is not None:
            check_layout_fits(layout, spec, url)
        self.layout = layout
        self.instruction = ""
        self.pending_rows = 0             # rows of the last chunk the runner executed, reported before the next query

    def _fault(self, exc: RemoteFault) -> PolicyError:
        return PolicyError(f"policy server {self.url}: {exc}", {"server": self.url, "fault": str(exc)})

    def reset(self, seed: int, instruction: str) -> None:
        self.instruction, self.pending_rows = instruction, 0
        try:
            self.transport.reset(seed, instruction)
        except RemoteFault as exc:
            raise self._fault(exc) from exc

    def act(self, observation: dict) -> np.ndarray:
        wire = {k: observation[k] for k in ("images", "state", "tactile") if k in observation}
        if self.layout is not None and "state" in wire:
            wire["state"] = self.layout.state.encode(wire["state"])
        wire.update(tick=int(observation.get("tick", 0)), instruction=self.instruction)
        try:
            if self.pending_rows:
                self.transport.executed(self.pending_rows)
            chunk = self.transport.chunk(wire, self.instruction)
        except RemoteFault as exc:
            raise self._fault(exc) from exc
        chunk = self._checked(chunk)
        if self.layout is not None:
            chunk = self.layout.action.decode(chunk)
        self.pending_rows = min(self.actions_per_query, len(chunk))
        return chunk

    def _checked(self, chunk) -> np.ndarray:
        dim = self.layout.dim if self.layout is not None else self.action_spec.dim
        try:
            arr = np.asarray(chunk, dtype=np.float64)
        except (TypeError, ValueError):
            arr = None
        if arr is None or arr.ndim != 2 or arr.shape[0] < 1 or arr.shape[1] != dim:
            got = f"shape {arr.shape}" if arr is not None else f"{type(chunk).__name__} {str(chunk)[:60]}"
            raise self._fault(RemoteFault(f"sent an action chunk of {got}; expected (rows >= 1, {dim}) joint targets"))
        if not np.isfinite(arr).all():
            raise self._fault(RemoteFault("sent non-finite actions"))
        return arr

    def close(self) -> None:
        self.transport.close()
