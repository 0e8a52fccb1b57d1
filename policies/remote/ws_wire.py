"""openpi's websocket wire format: msgpack, numpy arrays as {b"__ndarray__": True, b"data": raw bytes,
b"dtype": dtype.str, b"shape": shape} and numpy scalars as {b"__npgeneric__": True, ...}, exactly as the
`openpi_client.msgpack_numpy` module packs them, so either side can be a real openpi client or server.

Why not import `openpi-client` itself: its 0.1.2 release requires numpy < 2, which would downgrade the
numpy 2 that the rest of b2d (pandas 3, torch 2.13) is built on; this module reimplements its ~40 lines
of packing over the same `msgpack` package. Like openpi, object and void arrays are refused (no pickle).

The session: on connect the server sends its metadata (one packed dict); then each binary message from the
client is an observation dict and the server answers with an action dict ({"actions": [H, D]}). A server
that fails sends the error as a text message and closes the connection.
"""

from __future__ import annotations

import functools

import msgpack
import numpy as np


def pack_array(obj):
    if isinstance(obj, (np.ndarray, np.generic)) and obj.dtype.kind in ("V", "O", "c"):
        raise ValueError(f"Unsupported dtype: {obj.dtype}")
    if isinstance(obj, np.ndarray):
        return {b"__ndarray__": True, b"data": np.ascontiguousarray(obj).tobytes(), b"dtype": obj.dtype.str,
                b"shape": obj.shape}
    if isinstance(obj, np.generic):
        return {b"__npgeneric__": True, b"data": obj.item(), b"dtype": obj.dtype.str}
    return obj


def unpack_array(obj):
    if b"__ndarray__" in obj:
        dtype = np.dtype(obj[b"dtype"])
        if dtype.kind in ("V", "O"):
            raise ValueError(f"Unsupported dtype: {dtype}")
        return np.ndarray(buffer=obj[b"data"], dtype=dtype, shape=obj[b"shape"])
    if b"__npgeneric__" in obj:
        return np.dtype(obj[b"dtype"]).type(obj[b"data"])
    return obj


packb = functools.partial(msgpack.packb, default=pack_array)
unpackb = functools.partial(msgpack.unpackb, object_hook=unpack_array)
