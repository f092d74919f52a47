"""A hostile submission that forges the replies of its own policy process (test material for the protocol tests).

The policy process runs `policy_child` as `__main__`; a submission lives in that interpreter, so it can replace
the function that writes replies and send the evaluator anything. `Forger` sends, for one call, what the test
put in its observation under `forge`: `{"doc": JSON}` (a reply document; a `seq` of "$SEQ" becomes the real
one) or `{"raw": hex}` (bytes written to the socket as they are). `ForgedMessages` (an agent policy for
`evaluate --mode comm`) answers its second step with a forged message description: non-numeric `values` or a
non-integer `length`, chosen by its first observation.
"""

from __future__ import annotations

import sys

import numpy as np

_PENDING: dict[str, object] = {}


def _install() -> None:
    """Put the forging writer in front of the policy process's reply writer (once)."""
    main = sys.modules.get("__main__")
    original = getattr(main, "_reply", None)
    if original is None or getattr(original, "forging", False):
        return

    def forged(sock, reply):
        forge = _PENDING.pop("forge", None)
        if forge is None:
            return original(sock, reply)
        if "raw" in forge:
            sock.sendall(bytes.fromhex(forge["raw"]))
            return None
        doc = forge["doc"]
        if isinstance(doc, dict) and doc.get("seq") == "$SEQ":
            doc = {**doc, "seq": reply.get("seq")}
        return original(sock, doc)

    forged.forging = True
    main._reply = forged


class Forger:
    """Team or agent policy: moves forward; the reply to a call whose observation holds `forge` is forged."""

    def __init__(self) -> None:
        _install()

    def reset(self, info) -> None:
        return None

    def act(self, observation, inbox=None):
        if inbox is None:  # a team policy: {agent_id: observation}
            forge = next((o.get("forge") for o in observation.values() if "forge" in o), None)
            action = {agent: 1 for agent in observation}
        else:
            forge, action = observation.get("forge"), (1, None)
        if forge is not None:
            _PENDING["forge"] = forge
        return action


class ForgedMessages:
    """Agent policy: at its second step in an episode its reply carries a forged message description."""

    def __init__(self) -> None:
        _install()
        self.t = 0

    def reset(self, info) -> None:
        self.t = 0
        self.kind = 0

    def act(self, observation, inbox):
        self.t += 1
        if self.t == 1:
            self.kind = int(np.floor(abs(float(np.sum(observation["target"]))) * 1000)) % 2
        if self.t == 2:
            message = {"values": ["1", "x"]} if self.kind == 0 else {"length": 2.5, "values": [1.0, 2.0]}
            _PENDING["forge"] = {"doc": {"status": "ok", "seq": "$SEQ", "seconds": 0.0, "action": 1,
                                         "message": message}}
        return 1, None
