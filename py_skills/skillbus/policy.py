"""Who may send on which channel: the bus policy file (docs/security.md).

One rule per line, ``CHANNEL IDENTITY...``; ``#`` starts a comment. CHANNEL is a name or
a pattern in which ``*`` stands for any characters (``SB_SKPROC_*_REQ``), matched against
the channel without ``$SKILLBUS_NAMESPACE``; a robot's own channel (``r2/SB_ROBOT_ARM_CMD``)
is matched without its robot by a pattern that names none (``SB_ROBOT_ARM_CMD``: every
robot's) and whole by one that does (``r2/SB_ROBOT_*``); the first rule that matches decides; the
identity ``*`` is every holder of the key. A channel that no rule matches is refused.
The receivers enforce it (skillbus.auth), with the sender's identity from the
authenticated trailer. The C++ reader (common/src/auth.cpp) reads the same file.

>>> p = Policy.parse("SB_LOCKSTEP_CLOCK sim\\nSB_SKPROC_*_REQ skill_mgr\\n* *\\n")
>>> p.allows("sim", "SB_LOCKSTEP_CLOCK"), p.allows("intruder", "SB_LOCKSTEP_CLOCK")
(True, False)
>>> p.allows("skill_mgr", "SB_SKPROC_SKILLS_REQ"), p.allows("cli", "SB_SKPROC_SKILLS_REQ")
(True, False)
>>> p.allows("cli", "SB_SKILL_REQ")
True
>>> q = Policy.parse("r2/SB_ROBOT_ARM_CMD r2_skills\\nSB_ROBOT_ARM_CMD skills\\n")
>>> q.allows("r2_skills", "r2/SB_ROBOT_ARM_CMD"), q.allows("r2_skills", "r1/SB_ROBOT_ARM_CMD")
(True, False)
>>> q.allows("skills", "r1/SB_ROBOT_ARM_CMD"), q.allows("skills", "SB_ROBOT_ARM_CMD")
(True, True)
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass
from pathlib import Path

POLICY_ENV = "SKILLBUS_POLICY_FILE"


class PolicyError(ValueError):
    pass


@dataclass(frozen=True)
class Rule:
    pattern: str
    identities: frozenset[str]
    regex: re.Pattern[str]


class Policy:
    def __init__(self, rules: list[Rule], source: str = "") -> None:
        self.rules, self.source = rules, source
        self._namespace = os.environ.get("SKILLBUS_NAMESPACE", "")
        self._cache: dict[tuple[str, str], bool] = {}

    @staticmethod
    def parse(text: str, source: str = "<policy>") -> "Policy":
        rules = []
        for n, line in enumerate(text.splitlines(), 1):
            words = line.split("#", 1)[0].split()
            if not words:
                continue
            if len(words) < 2:
                raise PolicyError(f"{source}, line {n}: '{line.strip()}' names a channel and no identity "
                                  f"(a rule is CHANNEL IDENTITY...; * for any holder of the key)")
            if not re.fullmatch(r"[A-Za-z0-9_*/]+", words[0]):
                raise PolicyError(f"{source}, line {n}: '{words[0]}' is not a channel name or pattern "
                                  f"(letters, digits, _, / and *)")
            for ident in words[1:]:
                if len(ident.encode("utf-8", "surrogateescape")) > 255:
                    raise PolicyError(f"{source}, line {n}: the identity '{ident[:40]}...' is longer than 255 bytes, "
                                      f"which no sender can have (the trailer's room)")
            regex = re.compile("".join(".*" if c == "*" else re.escape(c) for c in words[0]))
            rules.append(Rule(words[0], frozenset(words[1:]), regex))
        return Policy(rules, source)

    @staticmethod
    def load(path: Path) -> "Policy":
        try:
            text = Path(path).read_text()
        except OSError as e:
            raise PolicyError(f"the bus policy {path}: {e.strerror}") from None
        return Policy.parse(text, str(path))

    def allows(self, identity: str, channel: str) -> bool:
        key = (identity, channel)
        hit = self._cache.get(key)
        if hit is None:
            name = channel[len(self._namespace):] if self._namespace and channel.startswith(self._namespace) else channel
            # A robot's own channel ("r2/SB_ROBOT_ARM_CMD"): a pattern without a robot is
            # about that channel of every robot; one with a robot about that robot's.
            base = name.split("/", 1)[-1]
            hit = False
            for r in self.rules:
                if r.regex.fullmatch(name if "/" in r.pattern else base):
                    hit = "*" in r.identities or identity in r.identities
                    break
            if len(self._cache) > 65536:  # (names come from the wire: bounded)
                self._cache.clear()
            self._cache[key] = hit
        return hit

    __call__ = allows

    def text(self) -> str:
        """The rules in the file's format, in order (for the C++ reader of the same rules).

        >>> Policy.parse("# who\\nSB_A* b a  # x\\n* *\\n").text()
        'SB_A* a b\\n* *\\n'
        """
        return "".join(f"{r.pattern} {' '.join(sorted(r.identities))}\n" for r in self.rules)


def from_env() -> Policy | None:
    path = os.environ.get(POLICY_ENV)
    return Policy.load(Path(path)) if path else None
