"""Seeded, bounded fuzzing of scenario files, their [campaign] tables and --set overrides.

Each mutant of a shipped scenario (the paper's and the landing ones) must
either load or be refused with one ScenarioError line; never another
exception. So must each mutant of a landing scenario's [campaign] table when
a campaign validates it (``campaign_spec_of``), and a table that passes must
draw finite values only. A seeded sample of the mutants that load is flown
through the command line, which must exit 0 (all outputs finite, strict
JSON), 2 (refused before any work, nothing written) or 3 (a failed flight,
one line, the partial trajectory marked failed).
"""

import csv
import json
import random

import pytest

from quadland.campaign.sampling import draws
from quadland.campaign.spec import DISTRIBUTIONS, MODES, campaign_spec_of
from quadland.cli import main
from quadland.exceptions import CampaignError, ScenarioError
from quadland.scenario import SCENARIO_DIR, load_scenario
from quadland.schema import LANDING_SCHEMA, PAPER_SCHEMA
from quadland.simulation import check_run as check_plan

SEED = 20261121
#: Value texts put in place of a key's value.
TOKENS = ['"x"', "true", "[]", "[1.0]", "[1.0, 2.0, 3.0, 4.0, 5.0]", "{a = 1}", "0", "-1",
          "1e308", "-1e308", "5e-324", "1e-308", "nan", "inf", "-inf", "9" * 400,
          "[" * 3000 + "]" * 3000, '"' + "a" * 5000 + '"', "1e9", "1e-9", "1e12", "2.5",
          '"rk"', "0x10", "1_000", "[nan, 0.0, 0.0]", "[1e308, 1e308, 1e308]", "2019-01-01",
          '"""a\nb"""', "[1, \"a\", true]", "-0.0", "1e-3", "100000", "0.5"]

PAPER = (SCENARIO_DIR / "paper.toml").read_text(encoding="utf-8")
LINES = PAPER.splitlines(keepends=True)


#: The landing scenarios' files, as lines.
LANDING_LINES = {name: (SCENARIO_DIR / f"{name}.toml").read_text(encoding="utf-8").splitlines(
    keepends=True) for name in ("highway", "turning", "ship")}


def _key_lines(lines):
    return [i for i, ln in enumerate(lines) if "=" in ln and not ln.lstrip().startswith("#")]


def _value_mutant(rng, lines=LINES):
    i = rng.choice(_key_lines(lines))
    key = lines[i].split("=", 1)[0]
    out = list(lines)
    out[i] = f"{key}= {rng.choice(TOKENS)}\n"
    return "".join(out).encode("utf-8")


def _file_mutant(rng, lines=LINES):
    kind = rng.randrange(7)
    out = list(lines)
    key_lines = _key_lines(lines)
    if kind == 0:                                          # delete a line
        del out[rng.choice(key_lines)]
    elif kind == 1:                                        # duplicate a line
        i = rng.choice(key_lines)
        out.insert(i, out[i])
    elif kind == 2:                                        # unknown key
        out.insert(rng.choice(key_lines), "surprise = 1\n")
    elif kind == 3:                                        # unknown or repeated section
        out.append(rng.choice(["[nonsense]\na = 1\n", "[simulation]\nseed = 1\n"]))
    elif kind == 4:                                        # truncated
        text = "".join(out).encode("utf-8")
        return text[:rng.randrange(len(text))]
    elif kind == 5:                                        # bad encoding
        text = "".join(out).encode("utf-8")
        if b"Section" in text:
            return text.replace(b"Section", b"Secti\xf3n\xff", 1)
        cut = rng.randrange(len(text))
        return text[:cut] + b"\xf3\xff" + text[cut:]
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
        sc = _load_or_refuse(path)
        loaded += sc is not None
        if sc is not None and sc.campaign_table is not None:
            _check_campaign(sc)                # what a campaign of it would check and draw
    assert 0 < loaded < 600                    # both outcomes occur


def _random_override(rng):
    section = rng.choice(list(PAPER_SCHEMA) + ["nosuch"])
    keys = list(PAPER_SCHEMA.get(section, {"x": None})) + ["bogus"]
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


def _landing_mutants(n):
    rng = random.Random(SEED + 3)
    out = []
    for k in range(n):
        lines = LANDING_LINES[rng.choice(sorted(LANDING_LINES))]
        out.append((_value_mutant if k % 3 else _file_mutant)(rng, lines))
    return out


def _one_line(exc):
    text = str(exc)
    assert "\n" not in text and 0 < len(text) < 400, text
    return text


def _check_campaign(sc, indices=range(3)):
    """Validate ``sc``'s table as a campaign does; a valid one must draw finite values only.

    Returns True for a valid table, False for one refused in one line.
    """
    try:
        spec = campaign_spec_of(sc)
    except (ScenarioError, CampaignError) as exc:
        _one_line(exc)
        return False
    for draw in draws(spec, indices):
        for column, text in draw.columns.items():
            assert text not in ("nan", "inf", "-inf") and "nan" not in text, (column, text)
        for disp in spec.dispersions:
            if disp.distribution not in ("uniform", "truncnorm") or disp.mode != "absolute":
                continue
            value = draw.values[disp.key]
            for e, v in enumerate(value if isinstance(value, list) else [value]):
                j = 0 if len(disp.low) == 1 else e
                assert disp.low[j] <= v <= disp.high[j], (disp.key, v)
        try:
            sc.replace(**draw.values)               # what a run flies, or "invalid"
        except ScenarioError as exc:
            _one_line(exc)
    return True


def test_landing_scenario_mutants_load_or_give_one_line(tmp_path):
    loaded = valid = 0
    for k, data in enumerate(_landing_mutants(450)):
        path = tmp_path / f"m{k}.toml"
        path.write_bytes(data)
        sc = _load_or_refuse(path)
        if sc is not None:
            loaded += 1
            if sc.campaign_table is not None:
                valid += _check_campaign(sc)
    assert 0 < loaded < 450 and valid > 0          # both outcomes occur


#: Values put in a dispersion entry's parameters: shapes, types and extreme numbers.
NUMBERS = [0.0, -0.0, 1.0, -1.0, 0.5, 2.0, 1e308, -1e308, 1.7976931348623157e308, 5e-324,
           -5e-324, 1e-300, 1e-30, 1e30, 1e300, float("inf"), float("-inf"), float("nan"),
           10 ** 400, -(2 ** 63), 3, True, "x"]
PARAMS = ("low", "high", "mean", "std", "values", "weights", "mode", "common", "also",
          "distribution", "bogus")


def _campaign_value(rng, name):
    """A value, plausible or not, for the parameter ``name`` of a dispersion entry."""
    pick = rng.randrange(10)
    if name == "mode" and pick < 7:
        return rng.choice(MODES + ("Relative", ""))
    if name == "distribution" and pick < 7:
        return rng.choice(sorted(DISTRIBUTIONS) + ["gamma"])
    if name == "common" and pick < 7:
        return rng.choice([True, False])
    if name == "also" and pick < 7:
        keys = [f"{s}.{k}" for s in LANDING_SCHEMA for k in LANDING_SCHEMA[s]]
        return rng.sample(keys + ["quadrotor.mas", "controller.k_w", "reference.e1d"],
                          rng.randrange(3))
    if name in ("values", "weights") and pick < 7:
        return [rng.choice(NUMBERS[:12] + [[1.0, 2.0, 3.0]]) for _ in range(rng.randrange(4))]
    if pick < 6:
        return rng.choice(NUMBERS)
    if pick < 8:
        return [rng.choice(NUMBERS) for _ in range(rng.choice([0, 1, 2, 3, 4]))]
    return rng.choice([{"a": 1}, [], "", [[1.0]]])


def _table_mutant(rng, table):
    """A copy of a campaign table with one to three mutations."""
    import copy

    table = copy.deepcopy(table)
    for _ in range(rng.randrange(1, 4)):
        kind = rng.randrange(9)
        entries = table.get("dispersions")
        if kind < 5 and isinstance(entries, dict) and entries:
            key = rng.choice(sorted(entries))
            entry = entries[key]
            name = rng.choice(PARAMS)
            if not isinstance(entry, dict):
                entries[key] = _campaign_value(rng, name)
            elif kind == 4 and name in entry:
                del entry[name]
            else:
                entry[name] = _campaign_value(rng, name)
        elif kind == 5 and isinstance(entries, dict):       # another key dispersed
            key = rng.choice([f"{s}.{k}" for s in LANDING_SCHEMA for k in LANDING_SCHEMA[s]]
                             + ["nosuch.key", "quadrotor"])
            entries[key] = {"distribution": rng.choice(sorted(DISTRIBUTIONS)),
                            **{p: _campaign_value(rng, p)
                               for p in rng.sample(PARAMS[:9], rng.randrange(4))}}
        elif kind == 6:                                        # the limits
            name = rng.choice(["sink_rate", "offset", "tilt_deg", "rotor_max", "aborts",
                               "settling_time_z_e", "nosuch"])
            if not isinstance(table.get("limits", {}), dict):
                table["limits"] = {}
            table.setdefault("limits", {})[name] = rng.choice(NUMBERS)
        elif kind == 7:                                        # runs, seed, sampling
            name = rng.choice(["runs", "seed", "sampling", "smapling"])
            table[name] = rng.choice(NUMBERS + ["sobol", "lhs", "grid", 0, 10 ** 7])
        else:                                                  # a whole part replaced
            table[rng.choice(["dispersions", "limits"])] = _campaign_value(rng, "low")
    return table


@pytest.mark.slow
def test_campaign_table_mutants_are_valid_or_one_line(tmp_path):
    import dataclasses
    import math

    rng = random.Random(SEED + 4)
    bases = {name: load_scenario(name) for name in ("highway", "ship")}
    outcomes = {True: 0, False: 0}
    for k in range(500):
        base = bases[rng.choice(sorted(bases))]
        table = _table_mutant(rng, base.campaign_table)
        sc = dataclasses.replace(base, campaign_table=table)
        valid = _check_campaign(sc)
        outcomes[valid] += 1
        # the scenario written with it (scenario.toml) loads back to the same table,
        # unless a NaN (never equal to itself) is in it
        path = tmp_path / f"t{k}.toml"
        path.write_text(sc.to_toml())
        again = load_scenario(path)
        if "nan" not in repr(table):
            assert again.campaign_table == table
        assert _check_campaign(again, ()) == valid or any(
            isinstance(v, float) and math.isnan(v) for v in _leaves(table))
    assert outcomes[True] > 0 and outcomes[False] > 0, outcomes


def _leaves(x):
    if isinstance(x, dict):
        for v in x.values():
            yield from _leaves(v)
    elif isinstance(x, list):
        for v in x:
            yield from _leaves(v)
    else:
        yield x


def _random_landing_override(rng):
    schemas = [LANDING_SCHEMA, PAPER_SCHEMA]
    schema = schemas[rng.randrange(4) == 0]                  # a paper-only key at times
    section = rng.choice(list(schema) + ["campaign", "nosuch"])
    if section == "campaign":
        key = rng.choice(["runs", "seed", "sampling", "dispersions", "limits", "bogus"])
        text = rng.choice(TOKENS + [
            '{"quadrotor.mass"={distribution="normal",std=1e308}}',
            '{"quadrotor.mass"={distribution="truncnorm",std=1e-300,low=0.5,high=1.0}}',
            '{"rbf.nodes"={distribution="choice",values=[10,20],weights=[1e308,1e308]}}',
            '{"initial.relative_velocity"={distribution="normal",mode="relative",std=1e308}}',
            '{"quadrotor.mass"={distribution="uniform",low=-0.1,high=0.1,also=["x.y"]}}',
            '{sink_rate = 0.5}', '"sobol"', '"lhs"'])
        return f"campaign.{key}={text}"
    keys = list(schema.get(section, {"x": None})) + ["bogus"]
    text = rng.choice(TOKENS + ["", "=", "[", '"', "1 2"])
    key = rng.choice(keys)
    return rng.choice([f"{section}.{key}={text}", f"{section}.{key}={text}",
                       f"{key}={text}", f"{section}..{key}={text}"])


def test_set_on_landing_scenarios_loads_or_gives_one_line():
    rng = random.Random(SEED + 5)
    loaded = 0
    for _ in range(500):
        name = rng.choice(["highway", "turning", "ship"])
        overrides = [_random_landing_override(rng) for _ in range(rng.randrange(1, 3))]
        try:
            sc = load_scenario(name, overrides)
            check_plan(sc)
        except ScenarioError as exc:
            _one_line(exc)
            continue
        loaded += 1
        if sc.campaign_table is not None:
            _check_campaign(sc, range(2))
    assert 0 < loaded < 500


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


@pytest.mark.slow
def test_a_sample_of_landing_and_campaign_mutants_runs_or_fails_cleanly(tmp_path, capfd):
    import dataclasses

    rng = random.Random(SEED + 6)
    # the sample: 6 mutants that load and 6 that are refused, spread over the 300 (about
    # a fifth load; a plain stride of 12 over all of them held no loading one whenever a
    # scenario file's new lines moved the draws so: P(none of 12) = 0.8^12, about 7 %)
    loads = []
    for k, data in enumerate(m for m in _landing_mutants(300) if m):
        path = tmp_path / f"l{k}.toml"
        path.write_bytes(data)
        loads.append((_load_or_refuse(path) is not None, data))
    sample = {want: [d for ok, d in loads if ok is want] for want in (True, False)}
    assert all(len(s) >= 6 for s in sample.values()), {w: len(s) for w, s in sample.items()}
    cases = [(want, d) for want, s in sample.items() for d in s[::len(s) // 6][:6]]
    statuses = set()
    for k, (loaded, data) in enumerate(cases):
        path, out = tmp_path / f"m{k}.toml", tmp_path / f"out{k}"
        path.write_bytes(data)
        status = main(["simulate", "--scenario", str(path), "--no-plots", "--out", str(out),
                       "--set", f"simulation.duration={rng.choice([0.2, 0.5])}"])
        err = capfd.readouterr().err.strip().splitlines()
        statuses.add(status)
        assert status in ((0, 3) if loaded else (2,)), (k, err)
        assert len(err) <= 1 and (status == 0 or len(err) == 1), (k, err)
        assert out.exists() == (status != 2), k
    assert 2 in statuses and statuses & {0, 3}
    # campaign tables: a two-run campaign of each of a sample of mutants (40: most
    # mutants are refused at once; after the table gained the quadratic drag's dispersion
    # the first 12 of this seed held no valid one, the first 40 hold two)
    base = load_scenario("highway")
    campaigns = set()
    for k in range(40):
        table = _table_mutant(rng, base.campaign_table)
        path, out = tmp_path / f"c{k}.toml", tmp_path / f"campaign{k}"
        path.write_text(dataclasses.replace(base, campaign_table=table).to_toml())
        status = main(["campaign", "--scenario", str(path), "--runs", "2", "--workers", "1",
                       "--no-plots", "--out", str(out), "--set", "simulation.duration=0.3"])
        err = capfd.readouterr().err.strip().splitlines()
        campaigns.add(status)
        assert status in (0, 2), (k, err)
        if status == 2:
            assert len(err) == 1 and not out.exists(), (k, err)
            continue
        _strict_json(out / "summary.json")
        with open(out / "runs.csv") as fh:
            rows = list(csv.reader(fh))
        assert len(rows) == 3 and all(v not in ("nan", "inf", "-inf") for r in rows for v in r)
    assert campaigns == {0, 2}
