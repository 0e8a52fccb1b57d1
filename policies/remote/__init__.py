"""Remote policies over the wire: the evaluation harness's TCP protocol and openpi's websocket protocol, a
client behind the policy interface (`RemotePolicy`) and a server for any b2d checkpoint (`make_server`)."""

from policies.remote.client import RemotePolicy
from policies.remote.server import make_server, server_url
from policies.remote.spec import RemoteSpec, load_remote_spec

__all__ = ["RemotePolicy", "RemoteSpec", "load_remote_spec", "make_server", "server_url"]
