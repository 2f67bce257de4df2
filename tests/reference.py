"""Independent NumPy expressions of the paper's kinematics, and the fuzzers' hard values,
for the tests."""

import math

import numpy as np

#: The landing plant's aerodynamics beyond eq. (2) switched off (ACTUATOR's quadratic drag
#: and ground effect): a test of eq. (2)'s plant alone packs these.
NO_AERO = dict(drag_quadratic=[0.0, 0.0, 0.0], rotor_radius=0.0, air_density=1.225)

#: The landing guidance's parameters for the guidance, quiescence and touchdown-policy
#: tests (each file overrides what it exercises): the shipped values, the touchdown
#: policy off.
GUIDANCE_P = dict(hover_height=3.0, align_radius=0.5, dwell_time=1.0, descent_speed=0.7,
                  descent_time=1.0, touchdown_speed=0.3, touchdown_height=0.2,
                  max_offset=0.2, max_relative_speed=0.5, max_deck_rise=0.8,
                  settle_time=0.1, marker_timeout=0.5, search_height=6.0,
                  commit_height=1.0, commit_horizon=2.5, calm_speed=0.4, motion_time=20.0,
                  fly_on=0.0, flare_height=0.15, flare_tilt=0.6, hold_time=0.05,
                  level_time=0.3, cut_time=0.5, aim_height=0.3, pivot_x=0.0, pivot_y=0.0,
                  pivot_h=0.0, descent_leash=0.0, leash_height=1e3,
                  withdraw_height=-1e3, calm_tilt=3.141592653589793,
                  contact_drop=0.0, crawl_pause=0.0, swerve_accel=0.0, crawl_gate=0.0,
                  crawl_gate_time=1e3, crawl_gate_floor=0.0,
                  crawl_gate_wait=1e3, crawl_gate_rise=1e3, crawl_gate_wait_height=1e3,
                  calm_lean=1.5707963267948966,
                  lean_time=1.0, lean_withdraw=0.0, abort_floor=-1e3, ground_airmode=1.0,
                  flare_deck_tilt=float(np.pi / 2), flare_deck_height=1e3,
                  crawl_abort_offset=1e3, crawl_gate_count_height=1e3,
                  crawl_abort_budget=1e6, withdraw_budget=1e6)


def euler_rate_matrix(phi, theta):
    """Rr of eq. (1), written out from the printed matrix."""
    return np.array([[1, np.tan(theta) * np.sin(phi), np.tan(theta) * np.cos(phi)],
                     [0, np.cos(phi), -np.sin(phi)],
                     [0, np.sin(phi) / np.cos(theta), np.cos(phi) / np.cos(theta)]])


def error_rate_matrix(phi, theta):
    """R = diag(1, Rr) of eq. (10)."""
    R = np.eye(4)
    R[1:, 1:] = euler_rate_matrix(phi, theta)
    return R


def rotation(eta):
    """Rz(psi) Ry(theta) Rx(phi) (body to E), multiplied out by hand."""
    phi, th, psi = eta
    cf, sf, ct, st = np.cos(phi), np.sin(phi), np.cos(th), np.sin(th)
    cp, sp = np.cos(psi), np.sin(psi)
    return np.array([[cp * ct, cp * st * sf - sp * cf, cp * st * cf + sp * sf],
                     [sp * ct, sp * st * sf + cp * cf, sp * st * cf - cp * sf],
                     [-st, ct * sf, ct * cf]])


def have_compiler() -> bool:
    """Whether quadland finds a C compiler (tests of generated C skip without one)."""
    from quadland.engine.build import have_compiler as found

    return found()


def extreme(rng: np.random.Generator, dtype) -> float:
    """A value of ``dtype``'s precision from one of the hard classes: NaN, infinities,
    signed zeros, subnormals, tiny normals, the largest values, large and small
    ones, or raw bits (NaN payloads, any class)."""
    fi, sign = np.finfo(dtype), rng.choice((-1.0, 1.0))
    kind = rng.integers(9)
    if kind == 0:
        return math.nan
    if kind == 1:
        return sign * math.inf
    if kind == 2:
        return sign * 0.0
    if kind == 3:   # subnormal
        return sign * float(fi.smallest_subnormal) * float(rng.integers(1, 2 ** 20))
    if kind == 4:   # tiny normal
        return sign * float(fi.tiny) * 10 ** rng.uniform(0, 5)
    if kind == 5:   # the largest values
        return sign * float(fi.max) * rng.uniform(0.25, 1.0)
    if kind == 6:   # large
        return sign * min(10 ** rng.uniform(3, math.log10(fi.max)), float(fi.max))
    if kind == 7:   # small
        return sign * 10 ** rng.uniform(math.log10(fi.tiny), -3)
    bits = np.dtype(dtype).itemsize * 8
    word = np.array([rng.integers(0, 2 ** bits, dtype=np.uint64)]).astype(
        np.uint64 if bits == 64 else np.uint32)
    return float(word.view(dtype)[0])


#: C helpers of the sanitized fuzz drivers (after ``#include "quadland.h"``): a seeded
#: xorshift generator, ``uniform()`` and ``extreme()``, the C twin of :func:`extreme`.
C_RANDOM = r"""
static unsigned long long seed;

static unsigned long long next(void)
{
    seed ^= seed >> 12;
    seed ^= seed << 25;
    seed ^= seed >> 27;
    return seed * 2685821657736338717ULL;
}

static double uniform(void)
{
    return (double)(next() >> 11) / 9007199254740992.0;
}

/* A ql_real with the given bits (the low ones in the float build). */
static ql_real from_bits(unsigned long long bits)
{
    ql_real v;
    if (sizeof v == 8) {
        memcpy(&v, &bits, sizeof v);
    } else {
        unsigned int b = (unsigned int)bits;
        memcpy(&v, &b, sizeof v);
    }
    return v;
}

/* Raw bits, signed zeros, subnormals, the extremes, NaN and infinities. */
static ql_real extreme(void)
{
    int dbl = sizeof(ql_real) == 8;
    ql_real sign = (next() & 1) ? -1 : 1;
    switch (next() % 8) {
    case 0: return from_bits(next());
    case 1: return sign * 0;
    case 2: return sign * from_bits(1 + next() % 1024);
    case 3: return sign * from_bits(dbl ? 0x0010000000000000ULL : 0x00800000ULL);
    case 4: return sign * from_bits(dbl ? 0x7FEFFFFFFFFFFFFFULL : 0x7F7FFFFFULL)
                   * (ql_real)(0.25 + 0.75 * uniform());
    case 5: return sign * (ql_real)pow(10.0, 30 * uniform());
    case 6: return (ql_real)NAN;
    default: return sign * (ql_real)INFINITY;
    }
}
"""


#: Flags of the address- and undefined-behaviour-sanitized builds of the fuzz tests.
SANITIZE = ("-fsanitize=address,undefined", "-fno-sanitize-recover=all",
            "-fno-omit-frame-pointer")


def run(cmd, **kw):
    """A subprocess with its output captured, bounded in time."""
    import subprocess

    return subprocess.run(cmd, capture_output=True, text=True, timeout=120, **kw)


def sanitizer_missing(cc: str, folder) -> str | None:
    """Why ``cc`` cannot build and run a sanitized program here, or None if it can."""
    from pathlib import Path

    folder = Path(folder)
    (folder / "probe.c").write_text("int main(void) { return 0; }\n")
    res = run([cc, *SANITIZE, "probe.c", "-o", "probe"], cwd=folder)
    if res.returncode != 0:
        return (f"{cc} cannot build with {' '.join(SANITIZE[:2])}: "
                f"{(res.stderr.strip().splitlines() or ['?'])[0]}")
    res = run([str(folder / "probe")])
    if res.returncode != 0:
        return (f"the sanitizer runtime does not run here: "
                f"{(res.stderr.strip().splitlines() or ['?'])[0]}")
    return None


def sanitized_drivers(tmp_path_factory, label: str, files, sources, driver: str) -> dict:
    """A fuzz driver built with the sanitizers against one part's flight C, both
    precisions, compiled in parallel: ``{"double": path, "float": path}``.

    ``files(precision)`` gives the part's C files by name, ``sources`` the ``.c``
    files to compile, ``driver`` the driver's C text. Skips the test when the
    compiler or the sanitizers' runtime is missing here.
    """
    import subprocess

    import pytest

    from quadland.engine import build

    cc = build.find_compiler()
    why = sanitizer_missing(cc, tmp_path_factory.mktemp("sanitizer_probe"))
    if why:
        pytest.skip(why)
    srcs = (*sources, "driver.c")
    procs, roots = [], {}
    for precision in ("double", "float"):
        root = tmp_path_factory.mktemp(f"sanitized_{label}_{precision}")
        for name, text in files(precision).items():
            (root / name).write_text(text)
        (root / "driver.c").write_text(driver)
        for src in srcs:
            procs.append(subprocess.Popen(
                [cc, *build.STRICT_CFLAGS, "-O1", *SANITIZE, "-c", src],
                cwd=root, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True))
        roots[precision] = root
    for p in procs:
        out, _ = p.communicate(timeout=600)
        assert p.returncode == 0, out
    exes = {}
    for precision, root in roots.items():
        objs = [f"{src[:-2]}.o" for src in srcs]
        res = run([cc, *SANITIZE, *objs, "-lm", "-o", "driver"], cwd=root)
        assert res.returncode == 0, res.stderr
        exes[precision] = root / "driver"
    return exes


#: The handover's velocity before "The handover's velocity from the GNSS" (docs/landing.md,
#: twentieth session): the cold start, the truth plus a draw from the filter's 0.5 m/s
#: ``p0_velocity``; main's bits exactly (highway's default 300 gives the nineteenth's
#: runs.csv). A replay of a campaign row measured before the twentieth session pins it.
HANDOVER_COLD = ["estimator.handover_velocity=p0", "estimator.p0_velocity=[0.5, 0.5, 0.5]"]

#: highway's contact switch before "highway: the graze switch" (docs/landing.md, eighteenth
#: session): it closed on 2 ms of the weight's load impulse, so a front foot's graze left it
#: open (the default seed's 314, 554 and 1193 bounced); the replays of highway's earlier rows
#: and default seed (through ``HIGHWAY_SIXTEENTH`` and ``HIGHWAY_GATE_SIXTEENTH``) pin it.
HIGHWAY_GRAZE = ["touchdown.switch_impulse=0.002"]

#: highway's descent leash before "The cars' offset at first contact: the tail taken apart, and
#: a shorter leash" (docs/landing.md, nineteenth session): 5 cm (now 2 cm); the replays of
#: highway's earlier rows and default seed (through ``HIGHWAY_SIXTEENTH`` and
#: ``HIGHWAY_GATE_SIXTEENTH``, and the eighteenth's graze and seventeenth's wait replays) pin it.
HIGHWAY_LEASH = ["landing.descent_leash=0.05"]

#: highway's crawl and land detector before "The crawl's gate and a ground contact that needs
#: the deck to carry the weight" (docs/landing.md, sixteenth session): no gate (the committed
#: crawl, the whole time to contact, no floor) and the detector's ground contact without the
#: thrust cue; the replays of highway's earlier campaign rows and default seed pin it.
HIGHWAY_SIXTEENTH = [*HIGHWAY_GRAZE, *HIGHWAY_LEASH, "landing.crawl_gate=0.0",
                     "landing.crawl_gate_floor=0.0", "landing.crawl_gate_time=1000.0",
                     "land_detector.contact_thrust=false"]

#: highway_100's friction before "highway_100 on fresh seeds: the creep under the magnets"
#: (docs/landing.md, twentieth session): the cap on the friction's slope at 1000 N s/m per foot
#: (the creep under the magnets 0.48 cm/s, not 0.22); the replays measured on the nineteenth's
#: file (and, through ``HIGHWAY_100_GATE``, every older one) pin it.
HIGHWAY_100_CREEP = ["gear.slip_damping_max=1000.0"]

#: highway_100's crawl before "highway_100: the crawl's gate on the predicted offset, its wait
#: over the whole crawl" (docs/landing.md, nineteenth session): no gate (the schema's
#: defaults: no gate, the whole time to contact, no floor, no wait); the replays measured on
#: the eighteenth's file (and, through ``HIGHWAY_100_GRAZE``, every older one) pin it (and its
#: friction, ``HIGHWAY_100_CREEP``).
HIGHWAY_100_GATE = [*HIGHWAY_100_CREEP, "landing.crawl_gate=0.0", "landing.crawl_gate_floor=0.0",
                    "landing.crawl_gate_time=1000.0", "landing.crawl_gate_wait=1000.0"]

#: highway_100's contact switch before "highway_100: the graze the switch did not feel"
#: (docs/landing.md, eighteenth session): it closed on 2 ms of the weight's load impulse, so a
#: front foot's graze (0.5-1.8 ms) left it open; the replays measured on the seventeenth's
#: file (and, through ``HIGHWAY_100_MARKER``, every older one) pin it (and its crawl,
#: ``HIGHWAY_100_GATE``).
HIGHWAY_100_GRAZE = [*HIGHWAY_100_GATE, "touchdown.switch_impulse=0.002"]

#: highway_100's withdrawal before "highway_100: the lane change's withdrawal down to the
#: front feet's contact" (docs/landing.md, seventeenth session): the swerve's hold past 0.3
#: m/s^2, no withdrawal at or below 0.25 m (the whole crawl); the replays measured on the
#: nested marker's file (and every older one) pin it.
HIGHWAY_100_MARKER = [*HIGHWAY_100_GRAZE, "landing.swerve_accel=0.3",
                      "landing.withdraw_height=0.25"]

#: highway's crawl gate as the sixteenth session shipped it, before "The crawl's gate: a wait
#: near the deck only" (docs/landing.md, seventeenth session): the floor at 0.10 m and no wait;
#: the replays of the sixteenth's gate (seed 13's run 133) pin it.
HIGHWAY_GATE_SIXTEENTH = [*HIGHWAY_GRAZE, *HIGHWAY_LEASH,
                          "landing.crawl_gate_floor=0.1",
                          "landing.crawl_gate_wait=1000.0",
                          "landing.crawl_gate_wait_height=1000.0"]

#: turning's command filter before "turning: the command filter at the corners' bound"
#: (docs/landing.md, twenty-first session): 10 rad/s (now 13); the replays of turning's rows
#: measured on the twentieth's file (and, through ``TURNING_SEVENTEENTH``, every older one)
#: pin it.
TURNING_FILTER = ["controller.filter_frequency=10.0"]

#: turning's crawl and land detector before "turning: a stiffer horizontal loop and the
#: crawl's gate" (docs/landing.md, eighteenth session): no gate (the committed crawl, no
#: floor, no wait) and the detector's ground contact without the thrust cue; the replays of
#: turning's earlier campaign rows and default seed pin it (and its command filter,
#: ``TURNING_FILTER``).
TURNING_SEVENTEENTH = [*TURNING_FILTER, "landing.crawl_gate=0.0", "landing.crawl_gate_floor=0.0",
                       "landing.crawl_gate_wait=1000.0", "landing.crawl_gate_wait_height=1000.0",
                       "land_detector.contact_thrust=false"]

#: highway_100's pad before "highway_100: what the offset at contact is made of, and the
#: nested marker" (docs/landing.md, sixteenth session): the large marker alone, lost at 0.45 m;
#: the replays measured on the paused crawl's file (and every older one) pin it (and its
#: withdrawal, ``HIGHWAY_100_MARKER``).
HIGHWAY_100_PAUSED = [*HIGHWAY_100_MARKER, "sensors.vision.small_range_max=0.0"]

#: highway_100's crawl before "highway_100: the crawl paused under the lower flare"
#: (docs/landing.md, fifteenth session): committed, not paused out of the align band; the
#: replays measured on the lower flare's file pin it (and its pad, ``HIGHWAY_100_PAUSED``).
HIGHWAY_100_FLARE = [*HIGHWAY_100_PAUSED, "landing.crawl_pause=false"]

#: highway_100's flare before "highway_100: the flare under the contact limit" (docs/landing.md,
#: fifteenth session): the tilt limit 58 deg from 0.15 m above touchdown; the replays measured
#: on the fourteenth's file pin it (and its committed crawl, ``HIGHWAY_100_FLARE``).
HIGHWAY_100_FOURTEENTH = [*HIGHWAY_100_FLARE, "touchdown.flare_tilt_deg=58.0",
                          "touchdown.flare_height=0.15"]

#: highway_100's guidance before "highway_100: the guidance holds through the lane change"
#: (docs/landing.md, fourteenth session): no hold while the pad swerves, a rising deck's
#: withdrawal down to the contact; the replays measured on the thirteenth's file pin it.
HIGHWAY_100_THIRTEENTH = [*HIGHWAY_100_FOURTEENTH, "landing.swerve_accel=0.0",
                          "landing.withdraw_height=-1000.0"]

#: highway_100's controller and descent before "highway_100: the observer and the leash"
#: (docs/landing.md, thirteenth session): no disturbance observer, integral action on x and
#: y, no leash; the replays measured on the twelfth's file pin it.
HIGHWAY_100_TWELFTH = ["controller.observer_frequency=[0.0, 0.0, 0.0]",
                       "controller.ki_p=[0.5, 0.5, 1.0]", "landing.descent_leash=0.0",
                       *HIGHWAY_100_THIRTEENTH]

#: highway_100's airframe before issue 19's "An airframe made for highway_100"
#: (docs/landing.md): the scenario as it was, bit for bit, for the reproducers that
#: were measured on it (benchmarks/highway_100_road.toml pins the same keys), with its
#: filter's target acceleration random walk, its friction's slope cap and its dwell of before
#: ("highway_100: the lane change was the filter's"); the later sessions' "before" first, so
#: that its own flare (34 deg) is the one flown.
HIGHWAY_100_OLD = [*HIGHWAY_100_TWELFTH,
                   "quadrotor.thrust_to_weight=2.0", "controller_model.thrust_to_weight=2.0",
                   "quadrotor.gear_height=0.2", "gear.feet_x=0.15", "gear.feet_y=0.125",
                   "controller.tilt_max_deg=45.0", "touchdown.flare_tilt_deg=34.0",
                   "touchdown.pivot_aim=1.0", "touchdown.lock_hold_force=100.0",
                   "landing.max_tilt_deg=48.7", "landing.pad_radius=0.5",
                   "landing.touchdown_speed=0.3",
                   "sensors.vision.half_angle=0.8901179185171081",
                   "sensors.vision.sigma0=0.02", "sensors.vision.sigma_per_m=0.01",
                   "sensors.vision.range_max=12.0", "estimator.vision_sigma0=0.02",
                   "estimator.vision_k_range=0.01", "estimator.q_at=[1e-06, 1e-06, 1e-06]",
                   "gear.slip_damping_max=300.0", "landing.dwell_time=1.0",
                   "touchdown.lock=magnet", "touchdown.level_time=0.1",
                   "touchdown.cut_time=0.1"]
