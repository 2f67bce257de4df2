"""Seeded, bounded fuzzing of scenario files and --set overrides.

Each mutant of the shipped scenario must either load or be refused with one
ScenarioError line; never another exception. A seeded sample of the mutants
that load is flown through the command line, which must exit 0 (all outputs
finite, strict JSON), 2 (refused before any work, nothing written) or 3 (a
failed flight, one line, the partial trajectory marked failed).
"""

import csv
import json
import random

import pytest

from quadland.cli import main
from quadland.exceptions import ScenarioError
from quadland.scenario import SCENARIO_DIR, SCHEMA, load_scenario
from quadland.simulate import check_plan

SEED = 20261121
#: Value texts put in place of a key's value.
TOKENS = ['"x"', "true", "[]", "[1.0]", "[1.0, 2.0, 3.0, 4.0, 5.0]", "{a = 1}", "0", "-1",
          "1e308", "-1e308", "5e-324", "1e-308", "nan", "inf", "-inf", "9" * 400,
          "[" * 3000 + "]" * 3000, '"' + "a" * 5000 + '"', "1e9", "1e-9", "1e12", "2.5",
          '"rk"', "0x10", "1_000", "[nan, 0.0, 0.0]", "[1e308, 1e308, 1e308]", "2019-01-01",
          '"""a\nb"""', "[1, \"a\", true]", "-0.0", "1e-3", "100000", "0.5"]

PAPER = (SCENARIO_DIR / "paper.toml").read_text(encoding="utf-8")
LINES = PAPER.splitlines(keepends=True)
KEY_LINES = [i for i, ln in enumerate(LINES) if "=" in ln and not ln.lstrip().startswith("#")]


def _value_mutant(rng):
    i = rng.choice(KEY_LINES)
    key = LINES[i].split("=", 1)[0]
    out = list(LINES)
    out[i] = f"{key}= {rng.choice(TOKENS)}\n"
    return "".join(out).encode("utf-8")


def _file_mutant(rng):
    kind = rng.randrange(7)
    out = list(LINES)
    if kind == 0:                                          # delete a line
        del out[rng.choice(KEY_LINES)]
    elif kind == 1:                                        # duplicate a line
        i = rng.choice(KEY_LINES)
        out.insert(i, out[i])
    elif kind == 2:                                        # unknown key
        out.insert(rng.choice(KEY_LINES), "surprise = 1\n")
    elif kind == 3:                                        # unknown or repeated section
        out.append(rng.choice(["[nonsense]\na = 1\n", "[simulation]\nseed = 1\n"]))
    elif kind == 4:                                        # truncated
        text = "".join(out).encode("utf-8")
        return text[:rng.randrange(len(text))]
    elif kind == 5:                                        # bad encoding
        return "".join(out).encode("utf-8").replace(b"Section", b"Secti\xf3n\xff", 1)
    else:                                                  # a byte-order mark
        return b"\xef\xbb\xbf" + "".join(out).encode("utf-8")
    return "".join(out).encode("utf-8")


def _mutants(n):
    rng = random.Random(SEED)
    return [(_value_mutant if k % 3 else _file_mutant)(rng) for k in range(n)]


def _load_or_refuse(path):
    try:
        sc = load_scenario(path)
        check_plan(sc)
        return sc
    except ScenarioError as exc:
        text = str(exc)
        assert "\n" not in text and 0 < len(text) < 400, text
        return None


def test_scenario_mutants_load_or_give_one_line(tmp_path):
    loaded = 0
    for k, data in enumerate(_mutants(600)):
        path = tmp_path / f"m{k}.toml"
        path.write_bytes(data)
        loaded += _load_or_refuse(path) is not None
    assert 0 < loaded < 600                    # both outcomes occur


def _random_override(rng):
    section = rng.choice(list(SCHEMA) + ["nosuch"])
    keys = list(SCHEMA.get(section, {"x": None})) + ["bogus"]
    text = rng.choice(TOKENS + ["", "=", "[", '"', "1 2"])
    key = rng.choice(keys)
    return rng.choice([f"{section}.{key}={text}", f"{key}={text}", f"{section}.{key}",
                       f"{section}..{key}={text}", f"={text}", f"{section}.{key}.x={text}"])


def test_set_mutants_load_or_give_one_line():
    rng = random.Random(SEED + 1)
    for _ in range(800):
        overrides = [_random_override(rng) for _ in range(rng.randrange(1, 3))]
        try:
            check_plan(load_scenario("paper", overrides))
        except ScenarioError as exc:
            text = str(exc)
            assert "\n" not in text and 0 < len(text) < 400, (overrides, text)


def _strict_json(path):
    def refuse(token):
        raise AssertionError(f"{path}: non-strict JSON token {token}")
    return json.loads(path.read_text(), parse_constant=refuse)


@pytest.mark.slow
def test_a_sample_of_mutants_flies_or_fails_cleanly(tmp_path, capfd):
    rng = random.Random(SEED + 2)
    cases = [m for m in _mutants(300) if m][::15]
    statuses = set()
    for k, data in enumerate(cases):
        path, out = tmp_path / f"m{k}.toml", tmp_path / f"out{k}"
        path.write_bytes(data)
        status = main(["simulate", "--scenario", str(path), "--no-plots", "--out", str(out),
                       "--set", f"simulation.duration={rng.choice([0.2, 0.5])}"])
        err = capfd.readouterr().err.strip().splitlines()
        statuses.add(status)
        assert status in (0, 2, 3), (k, err)
        if status == 2:
            assert len(err) == 1 and not out.exists(), (k, err)
            continue
        summary = _strict_json(out / "summary.json")
        assert summary["status"] == ("ok" if status == 0 else "failed")
        if status == 3:
            assert len(err) == 1, (k, err)
        with open(out / "trajectory.csv") as fh:
            rows = list(csv.reader(fh))
        assert all(v not in ("nan", "inf", "-inf") for row in rows[1:] for v in row)
    assert 0 in statuses and 2 in statuses
