#!/usr/bin/python3
"""Converts a state file of the old text formats (before issue 26) to the state archive.

Usage: convert_state.py OLD NEW        (NEW "-" writes to stdout)

Reads the demsolve state v2 (2D and 3D; "# demsolve state v2" on the first line; docs/dynamic.md
"State files", kind "dem") and the network state 1 of netsolve compact --save-state
("netdem-network-state 1"; docs/quasistatic.md "State file", kind "network") and the staggered
sintering state of netsolve sinter ("netdem-staggered-state 1"; docs/staggered.md "Restart state",
kind "staggered", with the seed and packing of the summary.json beside it as the record of
origin) and writes the JSON
state archive ("format": "netdem-state"). Every number is read with float() (float.fromhex for
the hexadecimal ones) and written with repr(), so every double keeps its bits; an
infinity is written as the string "inf". The converter checks the structure only: the ranges are
checked by the reader of the new file (demsolve --state), which names the field of a bad value.
Debian's /usr/bin/python3, standard library only.
"""
import json
import math
import os
import sys

LUDING_NAMES = ["k2", "k1_ratio", "kc_ratio", "alpha", "gamma_n", "gamma_t", "mu", "mu_wall", "T_melt", "T_var",
                "da_T", "delta_fluid_rel", "t0", "t0_sinter", "a0", "w0", "h", "rho_p", "m_wall", "gamma_wall",
                "T_radius_ref"]
LUDING_SWITCHES = ["stiffness_growth", "sliding_breaks_cohesion", "cooling_stiffness_update", "wall_sintering"]
COLUMNS = {2: ["x", "y", "vx", "vy", "omega", "theta", "radius", "radius_ref", "mass", "inertia", "fx", "fy",
               "torque"],
           3: ["x", "y", "z", "vx", "vy", "vz", "wx", "wy", "wz", "radius", "radius_ref", "mass", "inertia", "fx",
               "fy", "fz", "tx", "ty", "tz"]}


class ConvertError(Exception):
    pass


def real(token, what):
    """A double as the old reader read it (strtod); inf as "inf", NaN kept as the string "nan"
    (the new reader refuses it by name)."""
    try:
        v = float(token)
    except ValueError:
        raise ConvertError(f"cannot read {what} {token[:40]!r}")
    if math.isnan(v):
        return "nan"
    if math.isinf(v):
        return "inf" if v > 0 else "-inf"
    return v


class Lines:
    def __init__(self, text):
        self.lines = [l.rstrip("\r") for l in text.split("\n")]
        self.k = 0

    def next(self):
        while self.k < len(self.lines):
            s = self.lines[self.k]
            self.k += 1
            if s and not s.startswith("#"):
                return s
        raise ConvertError("unexpected end of file (truncated?)")

    def keyed(self, key):
        words = self.next().split()
        if not words or words[0] != key:
            raise ConvertError(f"line {self.k}: expected {key!r}")
        return words[1:]

    def peek_key(self):
        k = self.k
        s = self.next()
        self.k = k
        return s.split()[0] if s.split() else ""


def history(words, dim, what):
    n = 7 if dim == 2 else 9
    if len(words) < n:
        raise ConvertError(f"{what}: {len(words)} values, expected {n}")
    h = {"delta_max": real(words[0], "delta_max"), "delta0": real(words[1], "delta0"),
         "k2_line": real(words[2], "k2_line"), "k1_seen": real(words[3], "k1_seen")}
    if dim == 2:
        h["xi"] = real(words[4], "xi")
        rest = words[5:7]
    else:
        h["xi"] = [real(w, "xi") for w in words[4:7]]
        rest = words[7:9]
    h["fluid"] = int(rest[0]) != 0
    h["sliding"] = int(rest[1]) != 0
    return h


def convert_dem(text):
    r = Lines(text)
    r.k = 1  # the first line
    dim = 2
    if r.peek_key() == "dim":
        dim = int(r.keyed("dim")[0])
        if dim != 3:
            raise ConvertError("dim must be 3")
    j = {"format": "netdem-state", "kind": "dem", "version": 1, "dim": dim,
         "time": real(r.keyed("time")[0], "time"), "dt": real(r.keyed("dt")[0], "dt")}
    b = r.keyed("box")
    if len(b) != 1 + 2 * dim:
        raise ConvertError("box: wrong number of values")
    j["box"] = {"enabled": int(b[0]) != 0, "contact_walls": True,
                "min": [real(w, "box") for w in b[1:1 + dim]], "max": [real(w, "box") for w in b[1 + dim:]]}
    walls = []
    for name in (["wall_right", "wall_top"] if dim == 2 else ["wall_right", "wall_back", "wall_top"]):
        w = r.keyed(name)
        if len(w) != 6:
            raise ConvertError(f"{name}: wrong number of values")
        walls.append({"mode": w[0], "velocity": real(w[1], "velocity"), "pressure": real(w[2], "pressure"),
                      "mass": real(w[3], "mass"), "damping": real(w[4], "damping"),
                      "current_velocity": real(w[5], "velocity")})
    j["moving_walls"] = walls
    j["wall_force"] = [real(w, "wall force") for w in r.keyed("wall_force")]
    s = r.keyed("stress_sum")
    j["stress_sum"] = [real(w, "stress") for w in s[:dim * dim]]
    j["elastic"] = real(s[dim * dim], "elastic") if len(s) > dim * dim else 0.0
    t = r.keyed("thermal")
    j["thermal"] = {"T": real(t[0], "T"), "k1_Tt": real(t[1], "k1_Tt")}
    # the optional switches keep their defaults (true) when the file leaves them out
    luding = {name: True for name in LUDING_SWITCHES}
    while r.peek_key() == "param":
        p = r.keyed("param")
        if len(p) < 2:
            raise ConvertError("param: NAME VALUE expected")
        v = real(p[1], p[0])
        luding[p[0]] = (v != 0.0) if p[0] in LUDING_SWITCHES else v
    j["luding"] = luding
    j["law"] = "luding"
    n = int(r.keyed("particles")[0])
    header = r.next()
    if not header.startswith("id,"):
        raise ConvertError("expected the particle header line")
    cols = {c: [] for c in COLUMNS[dim]}
    for i in range(n):
        f = r.next().split(",")
        if len(f) != 1 + len(COLUMNS[dim]):
            raise ConvertError(f"particle {i}: {len(f)} fields")
        for c, v in zip(COLUMNS[dim], f[1:]):
            cols[c].append(real(v, c))
    j["particles"] = cols
    m = int(r.keyed("pairs")[0])
    pairs = {"i": [], "j": [], "history": []}
    for k in range(m):
        w = r.next().split()
        pairs["i"].append(int(w[0]))
        pairs["j"].append(int(w[1]))
        pairs["history"].append(history(w[2:], dim, f"pair {k}"))
    j["pairs"] = pairs
    m = int(r.keyed("wall_contacts")[0])
    wc = {"particle": [], "wall": [], "history": []}
    for k in range(m):
        w = r.next().split()
        wc["particle"].append(int(w[0]))
        wc["wall"].append(int(w[1]))
        wc["history"].append(history(w[2:], dim, f"wall contact {k}"))
    j["wall_contacts"] = wc
    if r.next() != "end":
        raise ConvertError("expected 'end' (truncated file?)")
    return j


def hexreal(token, what):
    """A hexadecimal (or decimal) double of the network and staggered states."""
    try:
        v = float.fromhex(token)
    except ValueError:
        return real(token, what)
    if math.isnan(v):
        return "nan"
    if math.isinf(v):
        return "inf" if v > 0 else "-inf"
    return v


def convert_network(text):
    lines = [l.split() for l in text.split("\n") if l.strip()]
    k = 0

    def take(key, count):
        nonlocal k
        if k >= len(lines):
            raise ConvertError(f"ends early, expected {key!r}")
        w = lines[k]
        k += 1
        if key and (not w or w[0] != key):
            raise ConvertError(f"record {k}: expected {key!r}")
        w = w[1:] if key else w
        if len(w) != count:
            raise ConvertError(f"record {k}: {len(w)} values, expected {count}")
        return w

    take("netdem-network-state", 1)
    pred = int(take("predictor", 1)[0]) == 1
    n = int(take("particles", 1)[0])
    p = {c: [] for c in ["x", "y", "theta", "r", "peripheral", "x_build", "y_build", "f_contact", "du_prev"]}
    for _ in range(n):
        w = take("", 13 if pred else 10)
        for c, t in zip(["x", "y", "theta", "r"], w[0:4]):
            p[c].append(hexreal(t, c))
        p["peripheral"].append(int(w[4]) != 0)
        p["x_build"].append(hexreal(w[5], "x_build"))
        p["y_build"].append(hexreal(w[6], "y_build"))
        p["f_contact"] += [hexreal(t, "f_contact") for t in w[7:10]]
        if pred:
            p["du_prev"] += [hexreal(t, "du_prev") for t in w[10:13]]
    j = {"format": "netdem-state", "kind": "network", "version": 1, "particles": p}
    sc = take("scalars", 3)
    j["solid_area"], j["initial_density"], j["box_area0"] = (hexreal(t, "scalar") for t in sc)
    b = [hexreal(t, "box0") for t in take("box0", 4)]
    j["box0"] = {"min": b[0:2], "max": b[2:4]}
    j["seed"] = int(take("seed", 1)[0])
    for key in ["box_deformation", "strain", "box_deformation_build", "dE_prev"]:
        j[key] = [hexreal(t, key) for t in take(key, 4)]
    m = int(take("pairs", 1)[0])
    pr = {c: [] for c in ["i", "j", "history", "E_form", "slip", "centre", "f_n", "f_t", "sliding"]}
    for _ in range(m):
        w = take("", 14)
        pr["i"].append(int(w[0]))
        pr["j"].append(int(w[1]))
        pr["history"].append({"u_max": hexreal(w[2], "u_max"), "f_t": hexreal(w[3], "f_t"), "sliding": int(w[4]) != 0})
        pr["E_form"].append([hexreal(t, "E_form") for t in w[5:9]])
        pr["slip"].append(hexreal(w[9], "slip"))
        pr["centre"].append(hexreal(w[10], "centre"))
        pr["f_n"].append(hexreal(w[11], "f_n"))
        pr["f_t"].append(hexreal(w[12], "f_t"))
        pr["sliding"].append(int(w[13]) != 0)
    j["pairs"] = pr
    t = take("timings", 11)
    names = ["assemble", "analyse", "factorise", "solve", "neighbours", "total"]
    j["timings"] = {c: hexreal(v, c) for c, v in zip(names, t[0:6])}
    for c, v in zip(["analyses", "factorisations", "solves", "increments", "newton_iterations"], t[6:11]):
        j["timings"][c] = int(v)
    take("end", 0)
    return j


OPT_REALS = ["dt_initial", "dt_max", "dt_min", "alpha", "eps_lim", "grow_below", "shrink_above"]
MAT_REALS = ["omega", "gamma_s", "gamma_gb", "D_vol0", "Q_vol", "deltaD_gb0", "Q_gb", "deltaD_s0", "Q_s", "c_III", "c_IV",
             "youngs_modulus", "poisson_ratio", "T_transus", "D_vol0_low", "Q_vol_low", "deltaD_gb0_low", "Q_gb_low",
             "deltaD_s0_low", "Q_s_low"]


def convert_staggered(text, origin):
    w = text.split()
    k = 0

    def word():
        nonlocal k
        if k >= len(w):
            raise ConvertError("unexpected end of file")
        k += 1
        return w[k - 1]

    def expect(key):
        got = word()
        if got != key:
            raise ConvertError(f"expected {key!r}, got {got[:40]!r}")

    def num(what="value"):
        return hexreal(word(), what)

    def integer():
        v = float.fromhex(word()) if w[k].startswith(("0x", "-0x")) else float(word())
        if v != math.floor(v):
            raise ConvertError("expected an integer")
        return int(v)

    expect("netdem-staggered-state")
    if integer() != 1:
        raise ConvertError("unknown state version")
    expect("options")
    o = {"strategy": integer()}
    for c in OPT_REALS:
        o[c] = num(c)
    o["new_contacts"] = integer() != 0
    o["x0_over_R"], o["x_max_over_R"] = num(), num()
    o["boundary_planes"] = integer() != 0
    for c in ["boundary_factor", "E", "nu", "gmres_tolerance"]:
        o[c] = num(c)
    o["refactor_iterations"] = integer()
    po = [num("plane_origin") for _ in range(3)]
    o["plane_origin"] = None if any(v == "nan" for v in po) else po  # NaN: the spheres' bounding box
    expect("material")
    m = {"name": word()}
    for c in MAT_REALS:
        m[c] = num(c)
    expect("profile")
    np_ = integer()
    if np_ == 0:
        profile = {"constant": num("T")}
    else:
        tt, TT = [], []
        for _ in range(np_):
            tt.append(num("t"))
            TT.append(num("T"))
        profile = {"times": tt, "temperatures": TT}
    expect("clock")
    clock = {"t": num("t"), "dt": num("dt"), "steps": integer(), "need_factor": integer() != 0,
             "last_iterations": integer()}
    nref = integer()
    clock["rhs_evals"] = integer()
    expect("timers")
    timers = {c: num(c) for c in ["detect", "integrate", "assemble", "factorise", "solve", "correct"]}
    expect("particles")
    n = integer()
    p = {c: [] for c in ["x", "y", "z", "r", "x0", "y0", "z0", "r0", "fixed_user", "fixed_plane"]}
    for _ in range(n):
        for c in ["x", "y", "z", "r", "x0", "y0", "z0", "r0"]:
            p[c].append(num(c))
        flags = integer()
        p["fixed_user"].append(flags & 63)
        p["fixed_plane"].append((flags >> 6) & 63)
    expect("contacts")
    nc = integer()
    cols = ["a", "b", "frozen", "status", "q", "q0", "t", "h", "steps", "rejected", "rhs_evals", "restarts",
            "t_created", "L_created", "dL_bar", "x_start"]
    c = {col: [] for col in cols}
    for _ in range(nc):
        c["a"].append(integer())
        c["b"].append(integer())
        c["frozen"].append(integer() != 0)
        c["status"].append(integer())
        c["q"].append([num("q") for _ in range(5)])
        c["q0"].append([num("q0") for _ in range(5)])
        c["t"].append(num("t"))
        c["h"].append(num("h"))
        for col in ["steps", "rejected", "rhs_evals", "restarts"]:
            c[col].append(integer())
        for col in ["t_created", "L_created", "dL_bar", "x_start"]:
            c[col].append(num(col))
    expect("factor")
    if integer() != nref:
        raise ConvertError("bad factor size")
    nfix = integer()
    fixed = [integer() for _ in range(nfix // 6)]
    el = {col: [] for col in ["e1", "e2", "e3", "lA0", "lB0", "Rm"]}
    for _ in range(nref):
        for col in ["e1", "e2", "e3"]:
            el[col].append([num(col) for _ in range(3)])
        for col in ["lA0", "lB0", "Rm"]:
            el[col].append(num(col))
    expect("end")
    return {"format": "netdem-state", "kind": "staggered", "version": 1, "options": o, "material": m,
            "profile": profile, "clock": clock, "timers": timers, "particles": p, "contacts": c,
            "factor": {"fixed": fixed, "elements": el}, "origin": origin}


def staggered_origin(path):
    """The record of origin of an old staggered state: the seed and the packing of the summary.json
    beside it (where netsolve sinter looked it up before issue 26), or null."""
    try:
        with open(os.path.join(os.path.dirname(os.path.abspath(path)), "summary.json")) as f:
            old = json.load(f)
    except (OSError, ValueError):
        return None
    if not isinstance(old, dict):
        return None
    rec = {}
    if isinstance(old.get("seed"), int) and old["seed"] >= 0:
        rec["seed"] = old["seed"]
    if "packing" in old:
        rec["packing"] = old["packing"]
    return rec or None


def convert(text, path=""):
    first = text.split("\n", 1)[0]
    if first.startswith("# demsolve state v2"):
        return convert_dem(text)
    if first.startswith("netdem-network-state"):
        return convert_network(text)
    if first.startswith("netdem-staggered-state"):
        return convert_staggered(text, staggered_origin(path))
    raise ConvertError(f"not an old state file (first line {first[:40]!r}); known: '# demsolve state v2', "
                       "'netdem-network-state 1', 'netdem-staggered-state 1'")


def main(argv):
    if len(argv) != 3:
        print(__doc__.strip().split("\n\n")[1], file=sys.stderr)
        return 2
    try:
        with open(argv[1], encoding="utf-8", errors="replace") as f:
            out = json.dumps(convert(f.read(), argv[1]), separators=(",", ":"), sort_keys=True, allow_nan=False) + "\n"
    except (OSError, ConvertError, ValueError, IndexError) as e:
        print(f"convert_state.py: {argv[1]}: {e}", file=sys.stderr)
        return 1
    if argv[2] == "-":
        sys.stdout.write(out)
    else:
        with open(argv[2], "w", encoding="utf-8") as f:
            f.write(out)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
