"""Submissions: parsing a policy spec and loading the team policy it names, in the current process.

A spec is one of:

- `package.module:attr` -- an importable module and an attribute of it;
- `path/to/file.py` or `path/to/file.py:attr` -- a Python file;
- `path/to/dir` or `path/to/dir:attr` -- a directory holding `policy.py` (and, typically, its weights);
- `baseline:NAME` -- a baseline shipped as a directory under `main_bench/evaluation/baselines/NAME/`.

The attribute defaults to `make_policy`, else `Policy`. It may be a class or a factory (any callable) returning
the team policy, or an object that already has `reset` and `act`. A class or factory is called with the keyword
arguments it declares among `root` (the submission's directory, so weights load from it) and `seed` (the
evaluation seed); it is called with no argument otherwise.

`load_policy` runs in the process that will call the policy: the isolated child of `PolicyProcess`.
"""

from __future__ import annotations

import hashlib
import importlib
import importlib.util
import inspect
import random
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import numpy as np

from ...errors import SubmissionError
from ...suggest import did_you_mean

#: Attribute names tried, in order, when a spec names none.
DEFAULT_ATTRS: tuple[str, ...] = ("make_policy", "Policy")
POLICY_FILE = "policy.py"
BASELINE_PREFIX = "baseline:"
BASELINES_DIR = Path(__file__).resolve().parents[1] / "baselines"

SpecKind = Literal["module", "file", "directory"]


class ProtocolError(SubmissionError):
    """The submission loaded but what it gave is not a team policy (no callable `reset` / `act`)."""


@dataclass(frozen=True)
class PolicySpec:
    """What to load: a module attribute, a file, or a directory's `policy.py`.

    `attr` is empty when the spec names none (then `DEFAULT_ATTRS` are tried). `root` is the directory handed to
    a factory's `root` parameter: the directory of the file, the submission directory, or None for a module
    (then the module's own directory is used at load time).
    """

    kind: SpecKind
    target: str
    attr: str = ""
    root: Path | None = None

    def __str__(self) -> str:
        return f"{self.target}:{self.attr}" if self.attr else self.target


def parse_spec(spec: str) -> PolicySpec:
    """Parse a submission spec (see the module docstring); a malformed or missing one raises `SubmissionError`."""
    text = spec.strip()
    if not text:
        raise SubmissionError("empty policy spec; give `package.module:attr`, `path/to/file.py[:attr]` or a directory")
    if text.startswith(BASELINE_PREFIX):
        return _baseline_spec(text)
    path_part, attr = _split_attr(text)
    path = Path(path_part).expanduser()
    if path.is_dir():
        policy_file = path / POLICY_FILE
        if not policy_file.is_file():
            raise SubmissionError(
                f"policy spec {spec!r}: directory {path} has no {POLICY_FILE}; a directory submission needs "
                f"{POLICY_FILE} defining {' or '.join(DEFAULT_ATTRS)}"
            )
        return PolicySpec("directory", str(policy_file.resolve()), attr, path.resolve())
    if path_part.endswith(".py") or "/" in path_part or "\\" in path_part:
        if not path.is_file():
            raise SubmissionError(f"policy spec {spec!r}: no such file or directory {path}; check the path")
        if path.suffix != ".py":
            raise SubmissionError(f"policy spec {spec!r}: {path} is not a .py file; give a Python file or a directory")
        return PolicySpec("file", str(path.resolve()), attr, path.resolve().parent)
    if not all(part.isidentifier() for part in path_part.split(".")):
        raise SubmissionError(
            f"policy spec {spec!r} is neither an existing path nor `package.module:attr`; "
            "give a module (my_pkg.policy:MyPolicy), a .py file or a directory with policy.py"
        )
    if attr and not all(part.isidentifier() for part in attr.split(".")):
        raise SubmissionError(f"policy spec {spec!r}: attribute {attr!r} is not a Python name")
    return PolicySpec("module", path_part, attr, None)


def _split_attr(text: str) -> tuple[str, str]:
    """Split `target:attr` at the last colon when what follows it is a dotted Python name."""
    head, sep, tail = text.rpartition(":")
    if sep and head and tail and all(part.isidentifier() for part in tail.split(".")):
        return head, tail
    if sep and head and not tail:
        raise SubmissionError(f"policy spec {text!r} ends with ':'; name the attribute after it or drop the colon")
    return text, ""


def _baseline_spec(text: str) -> PolicySpec:
    name = text[len(BASELINE_PREFIX):]
    folder = BASELINES_DIR / name
    if name.isidentifier() and (folder / POLICY_FILE).is_file():
        return PolicySpec("directory", str((folder / POLICY_FILE).resolve()), "", folder.resolve())
    from ..baselines import PRIVILEGED

    if name in PRIVILEGED:
        raise SubmissionError(
            f"policy spec {text!r}: baseline:{name} is built into the evaluator (it reads the simulator's state) "
            "and runs only through `main-bench evaluate --agent`; the standalone baselines a check or a "
            f"submission can load are {', '.join(BASELINE_PREFIX + b for b in standalone_baselines()) or 'none'}"
        )
    names = all_baselines()
    raise SubmissionError(f"policy spec {text!r}: no baseline {name!r}{did_you_mean(name, names, BASELINE_PREFIX)} "
                          f"(baselines: {', '.join(BASELINE_PREFIX + b for b in names)})")


def standalone_baselines() -> list[str]:
    """The names of the baselines shipped as policy directories (`baseline:NAME` loads like any submission)."""
    return sorted(p.parent.name for p in BASELINES_DIR.glob(f"*/{POLICY_FILE}")) if BASELINES_DIR.is_dir() else []


def all_baselines() -> list[str]:
    """Every `baseline:NAME` name: the evaluator's built-in (privileged) ones and the standalone ones."""
    from ..baselines import PRIVILEGED

    return sorted({*PRIVILEGED, *standalone_baselines()})


def seed_everything(seed: int) -> None:
    """Seed the global generators a policy may use: Python's `random`, NumPy's legacy one, and torch if loaded.

    Called in the policy's own process (never in the evaluator), at load and at every episode reset.
    """
    seed = int(seed) % (2**32)
    random.seed(seed)
    np.random.seed(seed)  # the policy's own process: policies may use it
    torch = sys.modules.get("torch")
    if torch is not None:
        torch.manual_seed(seed)


def instantiate_policy(spec: PolicySpec, seed: int) -> Any:
    """Import what `spec` names and build the policy object; any failure raises `SubmissionError`."""
    seed_everything(seed)
    module, root = _import(spec)
    names = (spec.attr,) if spec.attr else DEFAULT_ATTRS
    for name in names:
        obj = _getattr_dotted(module, name)
        if obj is not None:
            break
    else:
        raise SubmissionError(
            f"policy spec {spec}: {spec.target} defines no {' or '.join(repr(n) for n in names)}; "
            "define a class or factory with that name, or name it after a colon (file.py:MyPolicy)"
        )
    if not (inspect.isclass(obj) or (callable(obj) and not _has_protocol(obj))):
        return obj
    kwargs = _factory_kwargs(obj, root, seed)
    try:
        return obj(**kwargs)
    except Exception as exc:
        raise SubmissionError(f"policy spec {spec}: building {name}({_kw_text(kwargs)}) raised "
                              f"{type(exc).__name__}: {exc}") from exc


#: What a loaded object must offer, per role: the team policy of `central` mode, the agent policy of the others.
ROLES: dict[str, tuple[int, str, str]] = {
    "team": (1, "observations", "a team policy needs reset(info) and act(observations) -> {agent_id: action}"),
    "agent": (2, "observation, inbox", "an agent policy needs reset(info) and act(observation, inbox) -> "
              "(action, message)"),
}


def check_protocol(policy: Any, spec: PolicySpec | str, role: str = "team") -> Any:
    """Return `policy` if it has callable `reset(info)` and `act` with the role's arguments (`team`:
    observations; `agent`: observation, inbox); otherwise raise `ProtocolError`."""
    act_args, act_names, need = ROLES[role]
    missing = [m for m in ("reset", "act") if not callable(getattr(policy, m, None))]
    if missing:
        raise ProtocolError(
            f"policy spec {spec}: the loaded {type(policy).__name__} has no callable {' or '.join(missing)}; {need}"
        )
    for method, wanted in (("reset", 1), ("act", act_args)):
        if not _accepts_positional(getattr(policy, method), wanted):
            hint = "" if method != "act" else ("; an agent policy (act(observation, inbox)) runs with --mode silent "
                                               "or comm" if role == "team" else "; a team policy (act(observations)) "
                                               "runs with --mode central")
            raise ProtocolError(
                f"policy spec {spec}: {type(policy).__name__}.{method} does not accept {('one', 'two')[wanted - 1]} "
                f"positional argument{'s' if wanted > 1 else ''}; define {method}(self, "
                f"{'info' if method == 'reset' else act_names}){hint}"
            )
    return policy


def load_policy(spec: PolicySpec, seed: int, role: str = "team") -> Any:
    """Load the policy `spec` names into the current process, seeding global generators with `seed`.

    `role` `team` (a `TeamPolicy`, central mode), `agent` (an `AgentPolicy`, silent and comm modes) or `any`
    (either: what `check-agent` loads to learn the policy's kind, `policy_roles`). Raises
    `SubmissionError` (`ProtocolError` when the object lacks the role's `reset`/`act`) with the spec and the cause.
    """
    policy = instantiate_policy(spec, seed)
    if role != "any":
        check_protocol(policy, spec, role)
    elif not policy_roles(policy):
        check_protocol(policy, spec, "team")  # follows neither: the team policy's message says what is missing
    seed_everything(seed)
    return policy


def policy_roles(policy: Any) -> tuple[str, ...]:
    """The roles of `ROLES` whose protocol `policy` follows: `("team",)`, `("agent",)`, both (an `act(*args)`)
    or none."""
    roles = []
    for role in ROLES:
        try:
            check_protocol(policy, "", role)
        except ProtocolError:
            continue
        roles.append(role)
    return tuple(roles)


def _import(spec: PolicySpec) -> tuple[Any, Path | None]:
    if spec.kind == "module":
        try:
            module = importlib.import_module(spec.target)
        except Exception as exc:
            raise SubmissionError(f"policy spec {spec}: importing {spec.target} raised "
                                  f"{type(exc).__name__}: {exc}; is the package installed?") from exc
        file = getattr(module, "__file__", None)
        return module, spec.root or (Path(file).resolve().parent if file else None)
    path = Path(spec.target)
    if not path.is_file():
        raise SubmissionError(f"policy spec {spec}: {path} does not exist")
    folder = str(path.parent)
    if folder not in sys.path:
        sys.path.insert(0, folder)  # sibling modules of the submission import as usual
    name = "main_bench_submission_" + hashlib.sha1(str(path).encode()).hexdigest()[:12]
    if name in sys.modules:
        return sys.modules[name], spec.root
    module_spec = importlib.util.spec_from_file_location(name, path)
    if module_spec is None or module_spec.loader is None:
        raise SubmissionError(f"policy spec {spec}: {path} cannot be imported as a Python module")
    module = importlib.util.module_from_spec(module_spec)
    sys.modules[name] = module
    try:
        module_spec.loader.exec_module(module)
    except (Exception, SystemExit) as exc:
        del sys.modules[name]
        raise SubmissionError(f"policy spec {spec}: running {path.name} raised {type(exc).__name__}: {exc}") from exc
    return module, spec.root


def _getattr_dotted(module: Any, name: str) -> Any:
    obj = module
    for part in name.split("."):
        obj = getattr(obj, part, None)
        if obj is None:
            return None
    return obj


def _has_protocol(obj: Any) -> bool:
    return callable(getattr(obj, "reset", None)) and callable(getattr(obj, "act", None))


def _factory_kwargs(obj: Any, root: Path | None, seed: int) -> dict[str, Any]:
    try:
        params = inspect.signature(obj).parameters
    except (TypeError, ValueError):
        return {}
    kwargs: dict[str, Any] = {}
    if "root" in params:
        kwargs["root"] = root
    if "seed" in params:
        kwargs["seed"] = int(seed)
    return kwargs


def _kw_text(kwargs: dict[str, Any]) -> str:
    return ", ".join(f"{k}={v!r}" for k, v in kwargs.items())


def _accepts_positional(method: Any, n: int) -> bool:
    try:
        sig = inspect.signature(method)
    except (TypeError, ValueError):
        return True
    try:
        sig.bind(*([None] * n))
    except TypeError:
        return False
    return True
