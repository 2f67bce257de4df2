"""A campaign folder's identity: what must not change for it to be resumed.

``campaign.json`` (:func:`campaign_manifest`) records the quadland version
and source code, the libraries and the C compiler, the runs, the campaign
table and the scenario. :func:`check_folder` reads an existing folder (and
writes nothing): its manifest must be one quadland writes, of this
campaign, and its journal's rows runs of it; the refusal names the first
difference.
"""

from __future__ import annotations

import hashlib
from collections.abc import Mapping, Sequence
from pathlib import Path

from quadland.campaign.journal import MANIFEST, CampaignFolder, damaged_manifest, json_kind
from quadland.campaign.sampling import format_value
from quadland.campaign.spec import CampaignSpec
from quadland.exceptions import CampaignError
from quadland.scenario import Scenario

__all__ = ["MANIFEST_FORMAT", "code_fingerprint", "campaign_manifest", "check_folder"]

#: Format of campaign.json.
MANIFEST_FORMAT = 1


def code_fingerprint() -> str:
    """A hash of the source files of ``quadland`` and ``quadland_symbolic`` (Python, templates)."""
    import quadland
    import quadland_symbolic

    digest = hashlib.sha256()
    for package in (quadland, quadland_symbolic):
        root = Path(package.__file__).parent
        for path in sorted(p for p in root.rglob("*") if p.suffix in (".py", ".jinja")):
            digest.update(str(path.relative_to(root.parent)).encode() + b"\0")
            digest.update(path.read_bytes() + b"\0")
    return digest.hexdigest()[:16]


def campaign_manifest(scenario: Scenario, spec: CampaignSpec, runs: int) -> dict:
    from importlib.metadata import version

    from quadland import __version__
    from quadland.engine.build import compiler_version

    return {"format": MANIFEST_FORMAT, "quadland": __version__, "code": code_fingerprint(),
            "libraries": {name: version(name) for name in ("casadi", "numpy", "scipy")},
            "c_compiler": compiler_version(), "runs": runs,
            "campaign": spec.identity(), "scenario": scenario.to_dict()}


#: The type each entry of campaign.json must have (format 1).
_MANIFEST_TYPES = {"quadland": (str,), "code": (str,), "libraries": (dict,),
                   "c_compiler": (str, type(None)), "runs": (int,), "campaign": (dict,),
                   "scenario": (dict,)}


def _check_manifest(old: dict, path: Path) -> None:
    """Refuse a manifest of this format whose entries are not what quadland writes."""
    for key, kinds in _MANIFEST_TYPES.items():
        if key not in old:
            raise damaged_manifest(path, f"no \"{key}\"")
        value = old[key]
        if isinstance(value, bool) or not isinstance(value, kinds):
            raise damaged_manifest(path, f"\"{key}\" is {json_kind(value)}")
    if old["runs"] < 1:
        raise damaged_manifest(path, f"\"runs\" is {old['runs']}")
    if not all(isinstance(v, str) for v in old["libraries"].values()):
        raise damaged_manifest(path, "\"libraries\" holds something else than versions")
    for section, table in old["scenario"].items():
        if not isinstance(table, dict):
            raise damaged_manifest(path, f"\"scenario.{section}\" is {json_kind(table)}")


def _differences(old: Mapping, new: Mapping, prefix: str = "") -> list[str]:
    out = []
    for key in sorted(set(old) | set(new), key=str):
        a, b = old.get(key, "(absent)"), new.get(key, "(absent)")
        if isinstance(a, Mapping) and isinstance(b, Mapping):
            out += _differences(a, b, f"{prefix}{key}.")
        elif a != b:
            out.append(f"{prefix}{key}: {_short(a)} there, {_short(b)} here")
    return out


def _short(value) -> str:
    """A value of campaign.json, shortened for a message."""
    if isinstance(value, Mapping):
        text = str(dict(value))
    else:
        try:
            text = format_value(value)
        except (TypeError, ValueError):         # a null in a damaged campaign.json
            text = json_kind(value) if value is None else repr(value)
    text = " ".join(text.split())
    return text if len(text) <= 40 else text[:37] + "..."


def _check_resumable(old: dict, new: dict, path: Path) -> None:
    """Refuse, naming the first difference, a folder of another campaign or a damaged one."""
    manifest = path / MANIFEST
    if "format" not in old:
        raise damaged_manifest(manifest, "no \"format\"")
    if old["format"] != MANIFEST_FORMAT:
        raise CampaignError(f"out: {path} holds another campaign (it was written by another "
                            f"quadland: campaign format {_short(old['format'])}); choose a new "
                            "folder or run the campaign it holds")
    _check_manifest(old, manifest)
    why = None
    if old["quadland"] != new["quadland"]:
        why = f"quadland {' '.join(old['quadland'].split())[:40]} made it, this is " \
            f"{new['quadland']}"
    elif old["code"] != new["code"]:
        why = "quadland's source code changed since (its runs would not be comparable)"
    elif old["libraries"] != new["libraries"] or old["c_compiler"] != new["c_compiler"]:
        diff = _differences({**old["libraries"], "c_compiler": old["c_compiler"]},
                            {**new["libraries"], "c_compiler": new["c_compiler"]})
        why = f"a library changed: {diff[0]}"
    elif old["scenario"] != new["scenario"]:
        diff = _differences(old["scenario"], new["scenario"])
        why = f"the scenario changed: {diff[0]}" + \
            (f" (and {len(diff) - 1} more)" if len(diff) > 1 else "")
    elif old["campaign"] != new["campaign"]:
        diff = _differences(old["campaign"], new["campaign"], "campaign.")
        what = "the dispersions" if diff[0].startswith("campaign.dispersions") else \
            "the campaign"
        why = f"{what} changed: {diff[0]}"
    elif new["runs"] < old["runs"]:
        why = f"it holds a campaign of {old['runs']} runs; --runs can only grow"
    elif new["runs"] != old["runs"] and new["campaign"].get("sampling") == "lhs":
        why = (f"it holds a Latin hypercube of {old['runs']} runs, whose points depend on "
               "the number of runs")
    if why:
        raise CampaignError(f"out: {path} holds another campaign ({why}); choose a new folder "
                            "or run the campaign it holds")


def check_folder(folder: CampaignFolder, manifest: dict, header: Sequence[str]
                  ) -> dict[int, list[str]]:
    """The runs a folder of this campaign holds; refuse a folder that is not this
    campaign's, or whose journal is damaged (read only: nothing is created or changed)."""
    folder.check()
    old = folder.manifest()
    if old is not None:
        _check_resumable(old, manifest, folder.path)
    return folder.read_runs(header, manifest["runs"] if old is None else old["runs"])
