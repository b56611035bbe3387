#!/usr/bin/env python3
"""Adversarial input campaign for the fistage program.

Usage: python3 tests/adversarial/campaign.py PATH/TO/fistage [--quick] [--only CATEGORY]
                                                [--jobs N] [--timeout S]

Makes a scratch folder under the temp dir (kept, so the reproducers work),
generates many bad or hostile inputs per category, runs the program on each
with a timeout, classifies every outcome and prints a Markdown table, then
lists every crash, hang, wrong answer and unclear error with a one-line
reproducer. Exit status 1 if any crash, hang or wrong answer.

Python 3 standard library only.
"""

import argparse
import copy
import hashlib
import json
import math
import os
import re
import shlex
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import xml.etree.ElementTree as ET

try:
    import tomllib  # Python 3.11+
except ImportError:  # pragma: no cover
    tomllib = None
from concurrent.futures import ThreadPoolExecutor

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
NS = "urn:fistage:urdf:1"
FI = "{%s}" % NS
ET.register_namespace("fistage", NS)

CATEGORIES = ["robot", "scenario", "sweep", "robust", "identify", "modes", "flags", "output", "journal",
              "race"]
OUTCOMES = ["clear error", "right answer", "crash", "hang", "wrong answer", "unclear error"]
BAD = ("crash", "hang", "wrong answer")

# The mutation values of the brief.
VALUES = ["NaN", "inf", "-1", "0", "1e300", "1e-300", "", "abc"]
QUICK_VALUES = ["NaN", "-1", "0", "abc"]

TIMEOUT = 30.0
BIN = "fistage"  # replaced by main()


# ---------------------------------------------------------------------------
# Cases
# ---------------------------------------------------------------------------


class Case:
    """One run of the program.

    expect: "refuse" (must exit non-zero), "accept" (legitimate input: exit 0
    with good outputs expected), "either" (exit 0 must give good outputs; a
    refusal is judged by its message).
    needles: the culprit; a refusal mentioning any of them (case-insensitive)
    is a clear error.
    outputs: folders or files whose CSV/JSON contents are checked after exit 0.
    json_stdout: stdout is JSON and checked like an output file.
    guard: paths that existed before the run and must be unchanged after a
    failed run (and, with guard_always, after any run).
    post: extra oracle, called as post(case, result) -> problem string or None
    (after a run of any exit status when post_always, else after exit 0).
    during: called as during(process) while the program runs (a second
    program, a file put into its folder); what it finds is for post.
    """

    def __init__(self, cat, name, args, expect, needles, outputs=(), json_stdout=False,
                 guard=(), guard_always=False, post=None, cwd=None, during=None, post_always=False):
        self.cat = cat
        self.name = name
        self.args = [str(a) for a in args]
        self.expect = expect
        self.needles = [n for n in needles if n]
        self.outputs = list(outputs)
        self.json_stdout = json_stdout
        self.guard = list(guard)
        self.guard_always = guard_always
        self.post = post
        self.post_always = post_always
        self.during = during
        self.cwd = cwd or SCRATCH

    def repro(self):
        return "cd %s && %s %s" % (shlex.quote(self.cwd), shlex.quote(BIN),
                                   " ".join(shlex.quote(a) for a in self.args))


class Result:
    def __init__(self, rc, sig, stdout, stderr, timed_out, seconds):
        self.rc = rc
        self.sig = sig
        self.stdout = stdout
        self.stderr = stderr
        self.timed_out = timed_out
        self.seconds = seconds


SCRATCH = None
CASES = []
LEGIT_REFUSED = []  # (case, first stderr line): "accept" cases refused (not a failure column)


def add(*a, **k):
    c = Case(*a, **k)
    CASES.append(c)
    return c


def write(path, text, mode="w"):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, mode) as f:
        f.write(text)
    return path


def read(path):
    with open(path) as f:
        return f.read()


def tq(s):
    """TOML basic string."""
    return json.dumps(s)


# ---------------------------------------------------------------------------
# Running
# ---------------------------------------------------------------------------


def run_program(args, cwd, timeout=None, during=None):
    env = dict(os.environ)
    env["RUST_BACKTRACE"] = "0"  # short stderr; a panic still says "panicked"
    t0 = time.time()
    p = subprocess.Popen([BIN] + args, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                         stdin=subprocess.DEVNULL, env=env, start_new_session=True)
    if during is not None:
        during(p)
    timed_out = False
    try:
        out, err = p.communicate(timeout=timeout or TIMEOUT)
    except subprocess.TimeoutExpired:
        timed_out = True
        try:
            os.killpg(p.pid, signal.SIGKILL)  # only the group this campaign started
        except ProcessLookupError:
            pass
        out, err = p.communicate()
    rc = p.returncode
    sig = -rc if rc is not None and rc < 0 else None
    return Result(rc, sig, out.decode("utf-8", "replace"), err.decode("utf-8", "replace"),
                  timed_out, time.time() - t0)


def setup(args, cwd=None, expect_ok=True):
    """A preparatory run (not counted). Returns the Result."""
    r = run_program([str(a) for a in args], cwd or SCRATCH, timeout=120)
    if expect_ok and r.rc != 0:
        print("warning: setup run failed: %s\n  %s" % (" ".join(map(str, args)),
              (r.stderr.strip().splitlines() or [""])[0]), file=sys.stderr)
    return r


def snapshot(path):
    """Recursive listing with file hashes (None when absent)."""
    if not os.path.lexists(path):
        return None
    if os.path.isfile(path):
        with open(path, "rb") as f:
            return {"": "file:" + hashlib.sha256(f.read()).hexdigest()}
    snap = {}
    for root, dirs, files in os.walk(path):
        rel = os.path.relpath(root, path)
        snap[rel + "/"] = "dir"
        for n in files:
            p = os.path.join(root, n)
            try:
                with open(p, "rb") as f:
                    snap[os.path.join(rel, n)] = hashlib.sha256(f.read()).hexdigest()
            except OSError:
                snap[os.path.join(rel, n)] = "unreadable"
    return snap


# ---------------------------------------------------------------------------
# Oracles (all of them live here)
# ---------------------------------------------------------------------------

NONFINITE = {"nan", "+nan", "-nan", "inf", "+inf", "-inf", "infinity", "+infinity", "-infinity"}


def nonfinite_json(obj, where=""):
    if isinstance(obj, float):
        if not math.isfinite(obj):
            return where or "value"
    elif isinstance(obj, str):
        if obj.strip().lower() in NONFINITE:
            return (where or "value") + "=" + obj
    elif isinstance(obj, dict):
        for k, v in obj.items():
            w = nonfinite_json(v, where + "." + str(k))
            if w:
                return w
    elif isinstance(obj, list):
        for i, v in enumerate(obj):
            w = nonfinite_json(v, "%s[%d]" % (where, i))
            if w:
                return w
    return None


def modes_problem(doc, label):
    """A verdict that disagrees with the eigenvalues listed."""
    analyses = doc.get("analyses") if isinstance(doc, dict) else None
    if not isinstance(analyses, list):
        return None
    for a in analyses:
        if not isinstance(a, dict):
            continue
        verdict = a.get("verdict")
        stable = a.get("stable")
        says_stable = verdict == "stable" or (stable is True and verdict in (None, "stable"))
        modes = a.get("modes") or []
        reals = []
        scale = 1.0
        for m in modes:
            try:
                re_, im = float(m.get("real")), float(m.get("imag", 0.0))
            except (TypeError, ValueError):
                continue
            if math.isfinite(re_) and math.isfinite(im):
                scale = max(scale, math.hypot(re_, im))
            reals.append((re_, bool(m.get("neutral"))))
        eq = a.get("equilibrium")
        for re_, neutral in reals:
            tol = 1e-9 * scale if neutral else 0.0
            if says_stable and re_ > tol:
                return "%s: %s equilibrium verdict stable but an eigenvalue has real part %r" % (
                    label, eq, re_)
        mrp = a.get("max_real_part")
        if says_stable and isinstance(mrp, (int, float)) and mrp > 0:
            return "%s: %s verdict stable but max_real_part = %r" % (label, eq, mrp)
        if verdict == "unstable" and reals and all(r < 0 for r, _ in reals):
            return "%s: %s verdict unstable but every eigenvalue has negative real part" % (label, eq)
        if verdict == "stable" and stable is False or verdict == "unstable" and stable is True:
            return "%s: %s verdict %r but stable = %r" % (label, eq, verdict, stable)
    return None


def check_csv(path, text):
    lines = text.splitlines()
    for i, line in enumerate(lines):
        for cell in line.split(","):
            if cell.strip().lower() in NONFINITE:
                return "%s line %d has a non-finite cell %r" % (path, i + 1, cell)
    name = os.path.basename(path)
    if name in ("points.csv", "samples.csv") and lines:
        head = lines[0].split(",")
        if "stable_linear" in head and "max_real_eig" in head:
            a, b = head.index("stable_linear"), head.index("max_real_eig")
            for i, line in enumerate(lines[1:], 2):
                cells = line.split(",")
                if len(cells) <= max(a, b):
                    continue
                try:
                    eig = float(cells[b])
                except ValueError:
                    continue
                if cells[a].strip() == "true" and eig > 0:
                    return "%s line %d: stable_linear=true with max_real_eig=%s" % (path, i, cells[b])
    return None


def check_json_text(path, text):
    try:
        doc = json.loads(text)
    except ValueError as e:
        if re.search(r"(?i)(?<![\w.])-?(nan|inf|infinity)(?![\w.])", text):
            return "%s: not JSON, holds a nan/inf token" % path
        return "%s: not valid JSON (%s)" % (path, e)
    w = nonfinite_json(doc)
    if w:
        return "%s: non-finite value at %s" % (path, w)
    if os.path.basename(path) == "modes.json" or path == "stdout(modes --json)":
        return modes_problem(doc, path)
    return None


def check_outputs(case, res):
    """Problems of the outputs of a run that exited 0."""
    paths = []
    for o in case.outputs:
        if os.path.isdir(o):
            for root, _, files in os.walk(o):
                paths += [os.path.join(root, f) for f in files]
        elif os.path.isfile(o):
            paths.append(o)
    for p in sorted(paths):
        if p.endswith(".toml") and tomllib is not None:
            try:
                with open(p, "rb") as f:
                    tomllib.load(f)
            except Exception as e:  # noqa: BLE001 - any parse failure is the finding
                return "%s is not valid TOML (%s)" % (p, str(e).splitlines()[0])
            continue
        if not (p.endswith(".csv") or p.endswith(".json")):
            continue
        try:
            text = read(p)
        except (OSError, UnicodeDecodeError) as e:
            return "%s unreadable: %s" % (p, e)
        prob = check_csv(p, text) if p.endswith(".csv") else check_json_text(p, text)
        if prob:
            return prob
    if case.json_stdout:
        label = "stdout(modes --json)" if case.args[:1] == ["modes"] else "stdout(json)"
        prob = check_json_text(label, res.stdout)
        if prob:
            return prob
    return None


def classify(case, res, before):
    """-> (outcome, detail)."""
    if res.timed_out:
        return "hang", "no exit within %gs" % TIMEOUT
    if res.sig is not None:
        return "crash", "killed by signal %d" % res.sig
    if res.rc == 101 or "panicked" in res.stderr:
        line = next((l for l in res.stderr.splitlines() if "panicked" in l), "exit 101")
        return "crash", line.strip()[:300]
    changed = []
    for p, snap in before.items():
        if snapshot(p) != snap:
            changed.append(p)
    if res.rc != 0:
        if changed:
            return "wrong answer", "failed run changed pre-existing %s" % changed[0]
        if case.post and case.post_always:
            prob = case.post(case, res)
            if prob:
                return "wrong answer", prob
        low = res.stderr.lower()
        hit = [n for n in case.needles if n.lower() in low]
        first = first_line(res.stderr)
        # A number nobody can read (1e-300 printed in full decimal) makes
        # an error unclear whatever else it names.
        long_number = re.search(r"\d[\d.]{40,}", res.stderr)
        if long_number:
            return "unclear error", "%s (a number of %d digits)" % (first[:120], len(long_number.group(0)))
        if hit:
            return "clear error", first
        return "unclear error", "%s (no mention of %s)" % (first, " / ".join(map(repr, case.needles[:4])))
    # exit 0
    if case.guard_always and changed:
        return "wrong answer", "run changed %s" % changed[0]
    if case.expect == "refuse":
        return "wrong answer", "exit 0 on input that must be refused"
    prob = check_outputs(case, res)
    if prob:
        return "wrong answer", prob
    if case.post:
        prob = case.post(case, res)
        if prob:
            return "wrong answer", prob
    return "right answer", ""


def first_line(text):
    for l in text.splitlines():
        l = l.strip()
        if l:
            return l[:300]
    return "(empty stderr)"


# ---------------------------------------------------------------------------
# Shared scenario texts
# ---------------------------------------------------------------------------

ROBOT1 = os.path.join(REPO, "robots", "stage_1dof_fi.urdf")
ROBOT4 = os.path.join(REPO, "robots", "stage_4fi.urdf")
RIGID = os.path.join(REPO, "robots", "stage_1dof_rigid.urdf")


def set_line(text, key, value, table=None):
    """Replace `key = ...` (first occurrence inside `table`, None = top level)."""
    out, cur, done = [], None, False
    for line in text.splitlines():
        m = re.match(r"\s*\[\[?([^\]]+)\]\]?", line)
        if m:
            cur = m.group(1).strip()
        elif not done and cur == table and re.match(r"\s*%s\s*=" % re.escape(key), line):
            line = "%s = %s" % (key, value)
            done = True
        out.append(line)
    if not done:
        raise KeyError(key)
    return "\n".join(out) + "\n"


def fig05b(robot=ROBOT1, duration="0.5"):
    """scenarios/paper/fig05b_fi.toml, robot by absolute path, a shorter run."""
    t = read(os.path.join(REPO, "scenarios", "paper", "fig05b_fi.toml"))
    t = set_line(t, "robot", tq(robot))
    return set_line(t, "duration", duration)


def traverse(robot=ROBOT4, duration="0.5"):
    """scenarios/coupling/symmetric_traverse.toml, robot by absolute path, shorter."""
    t = read(os.path.join(REPO, "scenarios", "coupling", "symmetric_traverse.toml"))
    t = set_line(t, "robot", tq(robot))
    t = set_line(t, "duration", duration)
    return set_line(t, "window", "[0.25, 0.5]", "statistics")


_n = [0]


def fresh(prefix, ext=""):
    _n[0] += 1
    return os.path.join(SCRATCH, "%s%05d%s" % (prefix, _n[0], ext))


def scenario_file(cat, text, name="s"):
    return write(fresh("%s/%s" % (cat, name), ".toml"), text)


def run_and_check(cat, name, scen, expect, needles, cmds=("check", "run"), runtime=False):
    """`fistage check` and `fistage run` on one scenario. runtime: the fault shows only
    when the model runs (a run that cannot finish), so `check` may pass it."""
    for cmd in cmds:
        if cmd == "check":
            add(cat, name + " [check]", ["check", scen], "either" if runtime and expect == "refuse"
                else expect, needles)
        else:
            out = fresh("out/%s-run" % cat)
            add(cat, name + " [run]", ["run", scen, "--out", out, "--no-plots"], expect, needles,
                outputs=[out])


# ---------------------------------------------------------------------------
# 1. robot
# ---------------------------------------------------------------------------


def local(tag):
    return tag.split("}", 1)[1] if "}" in tag else tag


def qual(tag):
    return ("fistage:" + local(tag)) if tag.startswith(FI) else tag


def named_owner(path_elems):
    for e in reversed(path_elems):
        if "name" in e.attrib:
            return e.attrib["name"]
        for k in ("link",):
            if k in e.attrib:
                return e.attrib[k]
    return None


def inertia_physical(vals):
    """vals: ixx ixy ixz iyy iyz izz as floats -> True/False/None (undecidable)."""
    try:
        ixx, ixy, ixz, iyy, iyz, izz = vals
        if any(not math.isfinite(v) for v in vals):
            return False
        if max(abs(v) for v in vals) > 1e150:
            return None
        if min(ixx, iyy, izz) < 0:
            return False
        # positive semidefinite and the triangle inequalities of the principal moments
        m = [[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]]
        ev = sym3_eig(m)
        tol = 1e-9 * max(1e-300, max(abs(x) for x in ev))
        if min(ev) < -tol:
            return False
        a, b, c = ev
        if a + b < c - tol or a + c < b - tol or b + c < a - tol:
            return False
        return True
    except Exception:
        return None


def sym3_eig(m):
    p1 = m[0][1] ** 2 + m[0][2] ** 2 + m[1][2] ** 2
    q = (m[0][0] + m[1][1] + m[2][2]) / 3
    if p1 == 0:
        return sorted([m[0][0], m[1][1], m[2][2]])
    p2 = sum((m[i][i] - q) ** 2 for i in range(3)) + 2 * p1
    p = math.sqrt(p2 / 6)
    b = [[(m[i][j] - (q if i == j else 0)) / p for j in range(3)] for i in range(3)]
    det = (b[0][0] * (b[1][1] * b[2][2] - b[1][2] * b[2][1]) -
           b[0][1] * (b[1][0] * b[2][2] - b[1][2] * b[2][0]) +
           b[0][2] * (b[1][0] * b[2][1] - b[1][1] * b[2][0]))
    r = max(-1.0, min(1.0, det / 2))
    phi = math.acos(r) / 3
    e1 = q + 2 * p * math.cos(phi)
    e3 = q + 2 * p * math.cos(phi + 2 * math.pi / 3)
    return sorted([e1, 3 * q - e1 - e3, e3])


def num(v):
    try:
        return float(v)
    except ValueError:
        return None


def robot_expect(el, attr, old, new, root):
    """Expectation for attribute `attr` of element `el` set to `new` (None: deleted)."""
    tag = local(el.tag)
    fist = el.tag.startswith(FI)
    parent_tags = [local(p.tag) for p in root.iter() if el in list(p)]
    ptag = parent_tags[0] if parent_tags else ""
    fist_child = any(p.tag.startswith(FI) for p in root.iter() if el in list(p))
    if new is None:  # attribute deleted
        if tag == "stiffness" and attr == "xyz" and el.get("rpy") is None:
            return "refuse"  # nothing left of the isolator's only stiffness
        if tag in ("origin", "damping", "stiffness"):
            return "either"  # optional, default zero
        if fist or fist_child:
            return "refuse"
        if tag in ("link", "joint") and attr == "name":
            return "refuse"
        if tag in ("parent", "child", "mass") or attr == "type":
            return "refuse"
        if tag == "inertia":
            return "refuse"
        return "either"
    # names and references
    is_ref = attr in ("link", "parent", "child") or tag in ("parent", "child")
    if attr == "name" or is_ref:
        if new == "":
            return "refuse"
        if tag == "robot":
            return "either"
        if tag == "link" and attr == "name":
            return "refuse"  # every link is referenced
        if is_ref:
            return "refuse"  # no link of that name
        if tag in ("actuator", "sensor"):
            return "refuse"  # the scenario names them
        return "either"
    if attr == "type":
        return "refuse"
    vec = len(old.split()) > 1
    comps = [num(x) for x in old.split()]
    if new in ("", "abc", "NaN"):
        return "refuse"
    v = float(new)
    if new == "inf":
        if tag == "limit":
            return "either"
        return "refuse"
    if tag == "axis":
        vals = [v] + comps[1:]
        n = math.sqrt(sum(x * x for x in vals)) if v < 1e150 else float("inf")
        return "either" if abs(n - 1) < 1e-6 else "refuse"
    if tag == "mass":
        if v < 0:
            return "refuse"
        if v == 0:
            return "refuse"  # a moving link without mass (tests/bad_input.rs)
        return "either"
    if tag == "inertia":
        names = ["ixx", "ixy", "ixz", "iyy", "iyz", "izz"]
        vals = [float(el.attrib[n]) for n in names]
        vals[names.index(attr)] = v
        ok = inertia_physical(vals)
        return {True: "either", False: "refuse", None: "either"}[ok]
    if tag == "lugre":
        lug = {k: float(x) for k, x in el.attrib.items()}
        lug[attr] = v
        if lug["sigma0"] <= 0 or lug["v_s"] <= 0 or lug["f_c"] <= 0 or lug["f_s"] < lug["f_c"] \
                or lug["sigma1"] < 0 or lug["sigma2"] < 0:
            return "refuse"
        return "either"
    if tag == "limit":
        return "either"
    if tag in ("stiffness", "damping"):
        return "either"
    if tag == "origin":
        return "either"
    return "either"


def robot_needles(el, attr, chain, fname):
    n = [attr, qual(el.tag), local(el.tag)]
    owner = named_owner(chain)
    if owner:
        n.append(owner)
    return n


def robot_mutants(src_path, quick):
    """Yield (label, xml_text, expect, needles)."""
    text = read(src_path)
    root = ET.fromstring(text)
    base = os.path.basename(src_path)
    elems = list(root.iter())
    values = QUICK_VALUES if quick else VALUES

    def chain_of(r, target):
        path = []

        def walk(e):
            path.append(e)
            if e is target:
                return True
            for c in e:
                if walk(c):
                    return True
            path.pop()
            return False
        walk(r)
        return path

    def ser(r):
        return '<?xml version="1.0"?>\n' + ET.tostring(r, encoding="unicode")

    for idx, el in enumerate(elems):
        chain = chain_of(root, el)
        where = "/".join(qual(e.tag) + ("[%s]" % e.attrib["name"] if "name" in e.attrib else "")
                         for e in chain[1:])
        for attr, old in list(el.attrib.items()):
            for new in values + [None]:
                r = copy.deepcopy(root)
                e2 = list(r.iter())[idx]
                if new is None:
                    del e2.attrib[attr]
                    label = "%s: %s@%s deleted" % (base, where or "robot", attr)
                else:
                    parts = old.split()
                    val = " ".join([new] + parts[1:]) if len(parts) > 1 and new not in ("",) else new
                    e2.attrib[attr] = val
                    label = "%s: %s@%s=%r" % (base, where or "robot", attr, val)
                yield (label, ser(r), robot_expect(el, attr, old, new, root),
                       robot_needles(el, attr, chain, base))
            if len(old.split()) == 3 and not quick:
                r = copy.deepcopy(root)
                list(r.iter())[idx].attrib[attr] = " ".join(old.split()[:2])
                yield ("%s: %s@%s two components" % (base, where, attr), ser(r), "refuse",
                       robot_needles(el, attr, chain, base))
        if el is root:
            continue
        parent = next(p for p in root.iter() if el in list(p))
        pi = list(parent).index(el)
        owner = named_owner(chain)
        needles = [qual(el.tag), local(el.tag)] + ([owner] if owner else [])
        ltag = local(el.tag)
        fist = el.tag.startswith(FI) or parent.tag.startswith(FI)
        # delete the element
        r = copy.deepcopy(root)
        p2 = list(r.iter())[elems.index(parent)]
        p2.remove(list(p2)[pi])
        if ltag in ("link",) or ltag in ("parent", "child", "mass") or fist and ltag not in (
                "isolator", "friction", "origin", "damping"):
            exp = "refuse"
        elif ltag == "joint":
            exp = "refuse"  # its child link is then connected to nothing
        else:
            exp = "either"
        yield ("%s: delete <%s>" % (base, where), ser(r), exp, needles)
        # duplicate the element next to itself
        r = copy.deepcopy(root)
        p2 = list(r.iter())[elems.index(parent)]
        p2.insert(pi + 1, copy.deepcopy(list(p2)[pi]))
        exp = "refuse" if ("name" in el.attrib or fist or ltag in ("parent", "child", "mass",
                                                                  "inertia", "inertial")) else "either"
        yield ("%s: duplicate <%s>" % (base, where), ser(r), exp, needles + ["duplicate"])
        # rename the element's tag
        r = copy.deepcopy(root)
        e2 = list(r.iter())[idx]
        e2.tag = el.tag + "x"
        exp = "refuse" if (el.tag.startswith(FI) or fist or ltag in ("link", "joint", "parent",
                                                                   "child", "mass")) else "either"
        yield ("%s: rename <%s> to <%sx>" % (base, where, qual(el.tag)), ser(r), exp,
               needles + [qual(el.tag) + "x", local(el.tag) + "x"])


def robot_specials(src_path):
    """Hand-made hostile robot files: (label, text-or-bytes, expect, needles)."""
    t = read(src_path)
    base = os.path.basename(src_path)
    out = []

    def rep(label, a, b, expect, needles, count=1):
        if a not in t:
            print("warning: %s: %r not found" % (label, a), file=sys.stderr)
            return
        out.append((label, t.replace(a, b, count), expect, needles))

    fname = "bearing_friction" if "bearing_friction" in t else "friction_fl"
    for bad, exp in [("a,b", "refuse"), ("a b", "either"), ("", "refuse"), ('a"b', "refuse"),
                     ("x" * 10000, "either"), ("a\nb", "refuse"), ("é漢", "either"),
                     (" ", "refuse"), ("a.b", "either"), ("a[m]", "either")]:
        shown = bad if len(bad) < 20 else "x*%d" % len(bad)
        rep("%s: friction named %r" % (base, shown), 'name="%s"' % fname,
            'name="%s"' % bad.replace('"', "&quot;").replace("\n", "&#10;"), exp,
            [fname, "friction", "name"])
        rep("%s: sensor named %r" % (base, shown), 'name="encoder"',
            'name="%s"' % bad.replace('"', "&quot;").replace("\n", "&#10;"), "refuse",
            ["encoder", "sensor", "name"])
    # duplicate names across kinds
    if "bearing_friction" in t:
        rep(base + ": friction named like the isolator", 'name="bearing_friction"', 'name="isolator"',
            "refuse", ["isolator", "duplicate", "friction"])
        rep(base + ": two links named table", '<link name="bearing">', '<link name="table">',
            "refuse", ["table", "duplicate", "bearing"])
        rep(base + ": two joints named table_x", 'joint name="bearing_x"', 'joint name="table_x"',
            "refuse", ["table_x", "duplicate"])
        rep(base + ": sensor named like the actuator", 'name="encoder"', 'name="drive"',
            "refuse", ["drive", "duplicate", "encoder"])
        rep(base + ": missing parent", '<parent link="world"/>\n    <child link="table"/>',
            '<child link="table"/>', "refuse", ["parent", "table_x"])
        rep(base + ": missing child", '<parent link="world"/>\n    <child link="table"/>',
            '<parent link="world"/>', "refuse", ["child", "table_x"])
        rep(base + ": cycle table<->bearing",
            '<parent link="world"/>\n    <child link="bearing"/>',
            '<parent link="table"/>\n    <child link="bearing"/>', "either", ["bearing"])
        out.append((base + ": cycle world->table->bearing->table",
                    t.replace('<parent link="world"/>\n    <child link="bearing"/>',
                              '<parent link="table"/>\n    <child link="bearing"/>').replace(
                        "</robot>", '<joint name="back" type="fixed"><parent link="bearing"/>'
                        '<child link="table"/></joint>\n</robot>'),
                    "refuse", ["cycle", "table", "bearing", "back", "loop", "parent"]))
        rep(base + ": self-loop joint", '<parent link="world"/>\n    <child link="bearing"/>',
            '<parent link="bearing"/>\n    <child link="bearing"/>', "refuse", ["bearing"])
        rep(base + ": isolator parent==child", 'parent="table" child="bearing"',
            'parent="bearing" child="bearing"', "refuse", ["isolator", "bearing"])
        rep(base + ": joint child is world", '<child link="table"/>', '<child link="world"/>',
            "refuse", ["world", "table_x"])
        rep(base + ": friction on world", 'link="bearing">\n    <origin xyz="0 0 0"/>',
            'link="world">\n    <origin xyz="0 0 0"/>', "either", ["world", "bearing_friction"])
        rep(base + ": sensor on world", '<fistage:sensor name="encoder" link="table">',
            '<fistage:sensor name="encoder" link="world">', "either", ["world", "encoder"])
    else:
        rep(base + ": two links named bearing_fl", '<link name="bearing_fr">', '<link name="bearing_fl">',
            "refuse", ["bearing_fl", "duplicate", "bearing_fr"])
        rep(base + ": two frictions named friction_fl", 'name="friction_fr"', 'name="friction_fl"',
            "refuse", ["friction_fl", "duplicate"])
        rep(base + ": two isolators on one bearing", 'parent="table" child="bearing_fr"',
            'parent="table" child="bearing_fl"', "either", ["isolator_fr", "bearing_fl", "bearing_fr"])
        rep(base + ": floating joint parent is a bearing",
            '<parent link="world"/>\n    <child link="table"/>',
            '<parent link="bearing_fl"/>\n    <child link="table"/>', "either", ["table", "bearing_fl"])
        rep(base + ": table joint planar", 'type="floating"', 'type="planar"', "either",
            ["planar", "table"])
        rep(base + ": cycle via bearing",
            '<parent link="world"/>\n    <child link="bearing_fl"/>',
            '<parent link="bearing_fr"/>\n    <child link="bearing_fl"/>', "either", ["bearing_fl"])
    for typ in ["revolute", "continuous", "fixed", "floating", "planar", "spherical", "Prismatic"]:
        rep("%s: first prismatic joint as %s" % (base, typ), 'type="prismatic"', 'type="%s"' % typ,
            "refuse" if typ in ("spherical", "Prismatic") else "either",
            [typ, "type", "joint"] + (["table_x", "rail_fl"]))
    rep(base + ": fistage prefix bound to another URI", 'xmlns:fistage="urn:fistage:urdf:1"',
        'xmlns:fistage="urn:vendor:stage"', "refuse", ["urn:vendor:stage", "namespace"])
    rep(base + ": fistage namespace undeclared", ' xmlns:fistage="urn:fistage:urdf:1"', "",
        "refuse", ["fistage", "namespace", "prefix"])
    rep(base + ": default namespace is fistage", '<robot name=', '<robot xmlns="urn:fistage:urdf:1" name=',
        "either", ["namespace", "urn:fistage:urdf:1"])
    rep(base + ": other prefix bound to fistage URI", 'xmlns:fistage="urn:fistage:urdf:1"',
        'xmlns:fistage="urn:fistage:urdf:1" xmlns:fi="urn:fistage:urdf:1"', "accept", [])
    rep(base + ": fistage namespace version 2", 'urn:fistage:urdf:1', 'urn:fistage:urdf:2',
        "refuse", ["urn:fistage:urdf:2", "namespace"])
    rep(base + ": unknown fistage element", "</robot>", "<fistage:magnet name=\"m\"/></robot>",
        "refuse", ["fistage:magnet", "magnet"])
    rep(base + ": gazebo extension element", "</robot>", "<gazebo reference=\"table\"/></robot>",
        "either", ["gazebo"])
    rep(base + ": DOCTYPE with entity", '<?xml version="1.0"?>',
        '<?xml version="1.0"?>\n<!DOCTYPE r [<!ENTITY a "aaaaaaaaaa"><!ENTITY b "&a;&a;&a;&a;&a;&a;&a;&a;&a;&a;">'
        '<!ENTITY c "&b;&b;&b;&b;&b;&b;&b;&b;&b;&b;"><!ENTITY d "&c;&c;&c;&c;&c;&c;&c;&c;&c;&c;">]>',
        "either", ["doctype", "entity", "dtd"])
    rep(base + ": entity bomb used in a name", '<?xml version="1.0"?>',
        '<?xml version="1.0"?>\n<!DOCTYPE r [<!ENTITY a "aaaaaaaaaa"><!ENTITY b "&a;&a;&a;&a;&a;&a;&a;&a;&a;&a;">'
        '<!ENTITY c "&b;&b;&b;&b;&b;&b;&b;&b;&b;&b;"><!ENTITY d "&c;&c;&c;&c;&c;&c;&c;&c;&c;&c;">'
        '<!ENTITY e "&d;&d;&d;&d;&d;&d;&d;&d;&d;&d;"><!ENTITY f "&e;&e;&e;&e;&e;&e;&e;&e;&e;&e;">]>',
        "refuse", ["doctype", "entity", "dtd"])
    if out and out[-1][0].endswith("entity bomb used in a name"):
        lab, txt, exp, nd = out[-1]
        out[-1] = (lab, txt.replace('<robot name="', '<robot name="&f;', 1), exp, nd)
    rep(base + ": external entity", '<?xml version="1.0"?>',
        '<?xml version="1.0"?>\n<!DOCTYPE r [<!ENTITY x SYSTEM "file:///etc/passwd">]>',
        "either", ["doctype", "entity", "dtd"])
    for depth in (10, 1000, 100000):
        nest = "<a>" * depth + "</a>" * depth
        rep("%s: unknown element nested %d deep" % (base, depth), "</robot>", nest + "</robot>",
            "either" if depth == 10 else "refuse", ["nested", "<a>", "element", "depth", "deep"])
    for depth in (10, 1000, 100000):
        nest = "<fistage:x>" * depth + "</fistage:x>" * depth
        rep("%s: fistage element nested %d deep" % (base, depth), "</robot>", nest + "</robot>",
            "refuse", ["nested", "fistage:x", "element", "depth", "deep"])
    rep(base + ": truncated", "</robot>", "", "refuse", ["malformed", "xml", base])
    out.append((base + ": truncated half-way", t[: len(t) // 2], "refuse", ["malformed", "xml", "line"]))
    out.append((base + ": empty file", "", "refuse", ["empty", "xml", "robot", "urdf"]))
    out.append((base + ": whitespace only", "   \n\n", "refuse", ["empty", "xml", "robot", "urdf"]))
    out.append((base + ": binary garbage", bytes(range(256)) * 16, "refuse",
                ["utf-8", "utf8", "xml", "malformed", "robot", "urdf", "invalid"]))
    out.append((base + ": UTF-16 encoded", t.encode("utf-16"), "either", ["utf", "xml", "encoding"]))
    out.append((base + ": BOM prefix", "\ufeff" + t, "accept", []))
    out.append((base + ": CRLF line ends", t.replace("\n", "\r\n"), "accept", []))
    out.append((base + ": root element is not robot", t.replace("<robot ", "<robbot ", 1).replace(
        "</robot>", "</robbot>"), "refuse", ["robot", "robbot"]))
    out.append((base + ": two robots", t + "\n<robot name=\"y\"/>\n", "refuse", ["malformed", "xml", "robot"]))
    out.append((base + ": just <robot/>", '<robot name="r"/>', "refuse", ["world", "sensor", "encoder", "drive"]))
    return out


def gen_robot(quick):
    cat = "robot"
    for src, maker in [(ROBOT1, fig05b), (ROBOT4, traverse)]:
        if quick and src == ROBOT4:
            continue
        items = list(robot_mutants(src, quick)) + robot_specials(src)
        for label, text, expect, needles in items:
            path = fresh("robot/m", ".urdf")
            if isinstance(text, bytes):
                write(path, text, "wb")
            else:
                write(path, text)
            scen = scenario_file(cat, maker(robot=path))
            run_and_check(cat, label, scen, expect, needles + [os.path.basename(path)] *
                          (1 if any(k in label for k in ("empty", "garbage", "truncated", "whitespace",
                                                          "UTF-16", "two robots")) else 0))


# ---------------------------------------------------------------------------
# 2. scenario
# ---------------------------------------------------------------------------

TOML_VALUES = [("nan", "nan"), ("inf", "inf"), ("-1", "-1"), ("0", "0"), ("1e300", "1e300"),
               ("1e-300", "1e-300"), ('""', ""), ('"abc"', "abc"), ("true", "bool"),
               ("[1.0, 2.0]", "array")]
QUICK_TOML_VALUES = [("nan", "nan"), ("-1", "-1"), ("0", "0"), ('"abc"', "abc")]


def toml_lines(text):
    """(table, key, line index) of every `key = value` line."""
    cur, out = None, []
    for i, line in enumerate(text.splitlines()):
        m = re.match(r"\s*\[\[?([^\]]+)\]\]?", line)
        if m:
            cur = m.group(1).strip()
            continue
        m = re.match(r"\s*([A-Za-z_][\w-]*)\s*=", line)
        if m:
            out.append((cur, m.group(1), i))
    return out


def key_needles(table, key):
    full = "%s.%s" % (table, key) if table else key
    n = [full, "`%s`" % key, '"%s"' % key, "'%s'" % key, "%s =" % key]
    if len(key) >= 4:
        n.append(key)
    return n


NUMERIC_RULES = {
    # key: {kind: expectation}; kinds: nan inf -1 0 1e300 1e-300; others are type errors
    "duration": {"-1": "refuse", "0": "refuse", "1e300": "refuse", "1e-300": "either"},
    "velocity": {"-1": "either", "0": "accept", "1e300": "either", "1e-300": "accept"},
    "k": {"-1": "either", "0": "either", "1e300": "either", "1e-300": "either"},
    "c": {"-1": "either", "0": "either", "1e300": "either", "1e-300": "either"},
    "k_i": {"-1": "either", "0": "accept", "1e300": "either", "1e-300": "either"},
    "start": {"-1": "either", "0": "accept", "1e300": "either", "1e-300": "accept"},
}
STRING_KEYS = {"title", "robot", "sensor", "actuator", "kind"}
ENUM_KEYS = {"start": ("zero", "static", "slipping")}  # top-level start is an enum


def scenario_expect(table, key, kind):
    """Expectation for `table.key` set to a value of `kind`."""
    if kind == "delete":
        if key in ("robot", "duration", "sensor", "actuator", "kind"):
            return "refuse"
        if key in ("k", "c") and table == "controller":
            return "either"
        return "either"
    if key == "title":
        return "accept" if kind in ("", "abc") else "refuse"
    if key in STRING_KEYS or (table is None and key in ENUM_KEYS):
        return "refuse"  # wrong type, or names nothing
    if key == "window":
        return "refuse"  # a window is a pair
    if kind in ("nan", "inf", "", "abc", "bool", "array"):
        return "refuse"
    return NUMERIC_RULES.get(key, {}).get(kind, "either")


def gen_scenario(quick):
    cat = "scenario"
    values = QUICK_TOML_VALUES if quick else TOML_VALUES
    compensated = fig05b() + (
        '\n[compensation]\nkind = "lugre"\nelement = "bearing_friction"\nerror = { sigma0 = 0.5 }\n'
        'isolator = "dynamic"\n[dob]\nbandwidth = 50.0\nnominal_mass = 1.5\n')
    bases = [("fig05b_fi", fig05b()), ("fig05b_compensated", compensated)]
    if not quick:
        bases.append(("symmetric_traverse", traverse()))
    for bname, base in bases:
        lines = base.splitlines()
        for table, key, i in toml_lines(base):
            needles = key_needles(table, key)
            where = "%s.%s" % (table, key) if table else key
            for lit, kind in values:
                if key == "robot" and kind in ("", "abc"):
                    pass
                l2 = list(lines)
                l2[i] = "%s = %s" % (key, lit)
                scen = scenario_file(cat, "\n".join(l2) + "\n")
                extra = [kind] if kind in ("abc",) and key in STRING_KEYS | {"start"} else []
                run_and_check(cat, "%s: %s = %s" % (bname, where, lit), scen,
                              scenario_expect(table, key, kind), needles + extra,
                              runtime=(key == "duration" and kind == "1e300"))
            l2 = list(lines)
            del l2[i]
            scen = scenario_file(cat, "\n".join(l2) + "\n")
            run_and_check(cat, "%s: %s deleted" % (bname, where), scen,
                          scenario_expect(table, key, "delete"), needles)
            # duplicated key (TOML forbids it)
            l2 = list(lines)
            l2.insert(i + 1, lines[i])
            scen = scenario_file(cat, "\n".join(l2) + "\n")
            run_and_check(cat, "%s: %s duplicated" % (bname, where), scen, "refuse",
                          needles + ["duplicate", "line"])
            # renamed key (an unknown key)
            l2 = list(lines)
            l2[i] = re.sub(r"^(\s*)(\w[\w-]*)", lambda m: m.group(1) + m.group(2) + "x", lines[i])
            scen = scenario_file(cat, "\n".join(l2) + "\n")
            run_and_check(cat, "%s: %s renamed %sx" % (bname, where, key), scen, "refuse",
                          [key + "x"] + needles)
    b = fig05b()
    hand = [
        ("unknown top-level key", b + "\nspeed = 3\n", "refuse", ["speed"]),
        ("unknown key in [platform]", b.replace("[platform]", "[platform]\nacceleration = 1"),
         "refuse", ["acceleration"]),
        ("unknown key in [controller]", b + "kd = 3\n", "refuse", ["kd"]),
        ("unknown table", b + "\n[servo]\nk = 1\n", "refuse", ["servo"]),
        ("[solver] engine = nope", b + '\n[solver]\nengine = "nope"\n', "refuse", ["nope", "engine"]),
        ("engine = nope (top level)", 'engine = "nope"\n' + b, "refuse", ["nope", "engine"]),
        ("engine given twice", 'engine = "native"\n' + b + '\n[solver]\nengine = "rosenbrock"\n',
         "either", ["engine"]),
        ("engine = rosenbrock", b + '\n[solver]\nengine = "rosenbrock"\n', "accept", []),
        ("engine = RAPIER (case)", b + '\n[solver]\nengine = "RAPIER"\n', "refuse", ["RAPIER", "engine"]),
        ("unknown output signal", b + '\n[output]\nsignals = ["encoder.jerk"]\n', "refuse",
         ["encoder.jerk"]),
        ("unknown output element", b + '\n[output]\nsignals = ["nope.position"]\n', "refuse",
         ["nope.position", "nope"]),
        ("empty signal list", b + "\n[output]\nsignals = []\n", "either", ["signals"]),
        ("duplicated signal", b + '\n[output]\nsignals = ["encoder.position", "encoder.position"]\n',
         "either", ["encoder.position", "duplicate"]),
        ("signal name with comma", b + '\n[output]\nsignals = ["encoder.position,x"]\n', "refuse",
         ["encoder.position,x"]),
        ("signals not a list", b + '\n[output]\nsignals = "encoder.position"\n', "refuse", ["signals"]),
        ("unknown initial state", b + "\n[initial]\nnope.q = 1e-3\n", "refuse", ["nope.q", "nope"]),
        ("initial state NaN", b + "\n[initial]\n\"table_x.q\" = nan\n", "refuse", ["table_x.q"]),
        ("initial state inf", b + "\n[initial]\n\"bearing_x.v\" = inf\n", "refuse", ["bearing_x.v"]),
        ("initial state string", b + "\n[initial]\n\"table_x.q\" = \"abc\"\n", "refuse", ["table_x.q"]),
        ("initial integral without k_i", b + "\n[initial]\n\"controller.integral\" = 1\n", "refuse",
         ["controller.integral"]),
        ("initial bristle 1e300", b + "\n[initial]\n\"bearing_friction.z\" = 1e300\n", "either",
         ["bearing_friction.z"]),
        ("initial position 1 m", b + "\n[initial]\n\"table_x.q\" = 1.0\n", "either", ["table_x.q"]),
        ("window holding no samples", b + "\n[statistics]\nwindow = [0.2001, 0.2002]\n", "either",
         ["window", "statistics"]),
        ("window beyond the run", b + "\n[statistics]\nwindow = [10.0, 20.0]\n", "refuse",
         ["window", "statistics"]),
        ("window reversed", b + "\n[statistics]\nwindow = [0.4, 0.2]\n", "refuse", ["window"]),
        ("window empty", b + "\n[statistics]\nwindow = [0.3, 0.3]\n", "refuse", ["window"]),
        ("window NaN", b + "\n[statistics]\nwindow = [nan, 0.5]\n", "refuse", ["window"]),
        ("window negative start", b + "\n[statistics]\nwindow = [-1.0, 0.5]\n", "either", ["window"]),
        ("window three numbers", b + "\n[statistics]\nwindow = [0.1, 0.2, 0.3]\n", "refuse", ["window"]),
        ("window strings", b + '\n[statistics]\nwindow = ["a", "b"]\n', "refuse", ["window"]),
        ("sample_rate = 1e9", b + "\n[output]\nsample_rate = 1e9\n", "refuse", ["sample_rate"]),
        ("sample_rate = 0", b + "\n[output]\nsample_rate = 0\n", "refuse", ["sample_rate"]),
        ("sample_rate = -1", b + "\n[output]\nsample_rate = -1\n", "refuse", ["sample_rate"]),
        ("sample_rate = nan", b + "\n[output]\nsample_rate = nan\n", "refuse", ["sample_rate"]),
        ("sample_rate = 1e-3", b + "\n[output]\nsample_rate = 1e-3\n", "either", ["sample_rate"]),
        ("duration = 1e12", set_line(b, "duration", "1e12"), "refuse", ["duration"]),
        ("duration = 1e12 with sample_rate 1", set_line(b, "duration", "1e12") +
         "\n[output]\nsample_rate = 1\n", "refuse", ["duration"]),
        ("duration as string", set_line(b, "duration", '"5"'), "refuse", ["duration"]),
        ("duration integer", set_line(b, "duration", "1"), "accept", []),
    ]
    for v, exp in [("0", "refuse"), ("-1", "refuse"), ("1", "refuse"), ("2", "refuse"),
                   ("nan", "refuse"), ("inf", "refuse"), ("1e-300", "refuse"), ("1e-20", "either"),
                   ("1e-3", "accept"), ('"abc"', "refuse")]:
        hand.append(("solver rtol = %s" % v, b + "\n[solver]\nrtol = %s\n" % v, exp, ["rtol"]))
    for v, exp in [("0", "refuse"), ("-1", "refuse"), ("nan", "refuse"), ("1e-300", "refuse"),
                   ("1e300", "accept")]:
        hand.append(("solver max_step = %s" % v, b + "\n[solver]\nmax_step = %s\n" % v, exp, ["max_step"]))
    for v, exp in [("0", "refuse"), ("-1", "refuse"), ("nan", "refuse"), ("1e-300", "refuse"),
                   ("1", "either")]:
        hand.append(("solver max_steps = %s" % v, b + "\n[solver]\nmax_steps = %s\n" % v, exp, ["max_steps"]))
    hand += [
        ("overrides naming nothing", b + "\n[overrides.nope]\nf_c = 3\n", "refuse", ["overrides.nope", "nope"]),
        ("overrides unknown key", b + "\n[overrides.bearing_friction]\nmu = 0.3\n", "refuse", ["mu"]),
        ("overrides empty table of nothing", b + "\n[overrides.nope]\n", "refuse", ["nope"]),
        ("overrides f_c NaN", b + "\n[overrides.bearing_friction]\nf_c = nan\n", "refuse", ["f_c"]),
        ("overrides f_c > f_s", b + "\n[overrides.bearing_friction]\nf_c = 7.0\n", "refuse", ["f_c", "f_s"]),
        ("overrides sigma0 = 0", b + "\n[overrides.bearing_friction]\nsigma0 = 0\n", "refuse", ["sigma0"]),
        ("overrides sigma0 = -1", b + "\n[overrides.bearing_friction]\nsigma0 = -1\n", "refuse", ["sigma0"]),
        ("overrides v_s = 0", b + "\n[overrides.bearing_friction]\nv_s = 0\n", "refuse", ["v_s"]),
        ("overrides sigma1 = -1", b + "\n[overrides.bearing_friction]\nsigma1 = -1\n", "refuse", ["sigma1"]),
        ("overrides sigma2 = inf", b + "\n[overrides.bearing_friction]\nsigma2 = inf\n", "refuse", ["sigma2"]),
        ("overrides friction x = nan", b + "\n[overrides.bearing_friction]\nx = nan\n", "refuse", ["x"]),
        ("overrides mass = -1", b + "\n[overrides.table]\nmass = -1\n", "refuse", ["mass"]),
        ("overrides mass = 0", b + "\n[overrides.table]\nmass = 0\n", "refuse", ["mass"]),
        ("overrides mass = nan", b + "\n[overrides.table]\nmass = nan\n", "refuse", ["mass"]),
        ("overrides mass of world", b + "\n[overrides.world]\nmass = 1\n", "refuse", ["world"]),
        ("overrides isolator k_x = nan", b + "\n[overrides.isolator]\nk_x = nan\n", "refuse", ["k_x"]),
        ("overrides isolator k_x = -1", b + "\n[overrides.isolator]\nk_x = -1\n", "either", ["k_x"]),
        ("overrides isolator c_q", b + "\n[overrides.isolator]\nc_q = 1\n", "refuse", ["c_q"]),
        ("overrides actuator x = inf", b + "\n[overrides.drive]\nx = inf\n", "refuse", ["x", "drive"]),
        ("overrides actuator sigma0", b + "\n[overrides.drive]\nsigma0 = 1\n", "refuse", ["sigma0", "drive"]),
        ("overrides as a scalar", b + "\noverrides = 3\n", "refuse", ["overrides"]),
        ("gravity NaN", "gravity = [0.0, 0.0, nan]\n" + b, "refuse", ["gravity"]),
        ("gravity two components", "gravity = [0.0, -9.81]\n" + b, "refuse", ["gravity"]),
        ("gravity string", 'gravity = "down"\n' + b, "refuse", ["gravity"]),
        ("gravity 1e300", "gravity = [0.0, 0.0, -1e300]\n" + b, "either", ["gravity"]),
        ("rapier dt = 0", 'engine = "rapier"\n' + b + "\n[rapier]\ndt = 0\n", "refuse", ["dt"]),
        ("rapier dt = -1", 'engine = "rapier"\n' + b + "\n[rapier]\ndt = -1\n", "refuse", ["dt"]),
        ("rapier dt = nan", 'engine = "rapier"\n' + b + "\n[rapier]\ndt = nan\n", "refuse", ["dt"]),
        ("rapier dt = 1e-300", 'engine = "rapier"\n' + b + "\n[rapier]\ndt = 1e-300\n", "refuse", ["dt"]),
        ("rapier dt = 1", 'engine = "rapier"\n' + b + "\n[rapier]\ndt = 1\n", "either", ["dt"]),
        ("rapier stop on missing joint", 'engine = "rapier"\n' + b +
         '\n[[rapier.stop]]\njoint = "nope"\nupper = 1e-3\n', "refuse", ["nope"]),
        ("rapier stop lower > upper", 'engine = "rapier"\n' + b +
         '\n[[rapier.stop]]\njoint = "table_x"\nlower = 1e-3\nupper = -1e-3\n', "refuse",
         ["lower", "upper", "table_x"]),
        ("rapier stop restitution 2", 'engine = "rapier"\n' + b +
         '\n[[rapier.stop]]\njoint = "table_x"\nupper = 1e-3\nrestitution = 2\n', "refuse",
         ["restitution"]),
        ("rapier stop with native engine", b + '\n[[rapier.stop]]\njoint = "table_x"\nupper = 1e-3\n',
         "refuse", ["rapier", "native", "collider"]),
        ("rapier payload negative mass", 'engine = "rapier"\n' + b +
         '\n[rapier.payload]\nlink = "table"\nsize = [0.01, 0.01, 0.01]\nmass = -1\n'
         'position = [0, 0, 0.02]\nfriction = 0.5\n', "refuse", ["mass", "payload"]),
        ("rapier payload zero size", 'engine = "rapier"\n' + b +
         '\n[rapier.payload]\nlink = "table"\nsize = [0, 0.01, 0.01]\nmass = 0.1\n'
         'position = [0, 0, 0.02]\nfriction = 0.5\n', "refuse", ["size", "payload"]),
        ("reference kind nope", b + '\n[reference]\nkind = "nope"\n', "refuse", ["nope", "kind"]),
        ("reference sine without amplitude", b + '\n[reference]\nkind = "sine"\nfrequency = 1\n',
         "refuse", ["amplitude"]),
        ("reference sine frequency nan", b + '\n[reference]\nkind = "sine"\namplitude = 1e-3\nfrequency = nan\n',
         "refuse", ["frequency"]),
        ("reference sine frequency 1e12", b + '\n[reference]\nkind = "sine"\namplitude = 1e-3\nfrequency = 1e12\n',
         "either", ["frequency"]),
        ("reference p2p duration 0", b + '\n[reference]\nkind = "p2p"\nstart = 0.0\nduration = 0\ndistance = 1e-3\n',
         "refuse", ["duration"]),
        ("reference p2p duration -1", b + '\n[reference]\nkind = "p2p"\nstart = 0.0\nduration = -1\ndistance = 1e-3\n',
         "refuse", ["duration"]),
        ("reference csv missing file", b + '\n[reference]\nkind = "csv"\nfile = "nope.csv"\n', "refuse",
         ["nope.csv"]),
        ("robot is a folder", set_line(b, "robot", tq(SCRATCH)), "refuse", [os.path.basename(SCRATCH), "robot"]),
        ("robot is /dev/zero", set_line(b, "robot", tq("/dev/zero")), "refuse", ["/dev/zero"]),
        ("robot is the scenario itself", None, "refuse", ["robot", "xml", "malformed"]),
        ("start = slipping", set_line(b, "duration", "0.5") + "", "accept", []),
    ]
    hand[-1] = ("start = slipping", 'start = "slipping"\n' + b, "accept", [])
    runtime_only = ("duration = 1e12", "solver rtol = 1e-300", "solver max_step = 1e-300",
                    "solver max_steps = 0", "solver max_steps = 1", "rapier dt = 1e-300")
    for label, text, exp, needles in hand:
        if text is None:
            path = fresh("scenario/self", ".toml")
            text = set_line(b, "robot", tq(path))
            write(path, text)
            run_and_check(cat, label, path, exp, needles)
            continue
        scen = scenario_file(cat, text)
        run_and_check(cat, label, scen, exp, needles, runtime=label in runtime_only)
    # files that are not TOML
    for label, data in [("empty scenario", b""), ("binary scenario", bytes(range(256)) * 8),
                        ("scenario is JSON", b'{"robot": "x", "duration": 1}'),
                        ("scenario with NUL", b"robot = \"x\0y\"\nduration = 1\n")]:
        path = write(fresh("scenario/raw", ".toml"), data, "wb")
        run_and_check(cat, label, path, "refuse", [os.path.basename(path), "toml", "line", "missing"])
    run_and_check(cat, "scenario file missing", os.path.join(SCRATCH, "nope.toml"), "refuse", ["nope.toml"])

# ---------------------------------------------------------------------------
# 3. sweep
# ---------------------------------------------------------------------------

SWEEP_AXES = """
[[sweep.axis]]
parameter = "controller.k"
from = 1e4
to = 1e5
points = 2

[[sweep.axis]]
parameter = "controller.c"
from = 50.0
to = 200.0
points = 3
spacing = "log"
"""


def sweep_text(sweep_head='analysis = "both"\nduration = 0.2\n', axes=SWEEP_AXES, base=None):
    b = base or fig05b(duration="0.2")
    return b + "\n[sweep]\n" + sweep_head + axes


def axis(parameter, frm, to, points, spacing=None, extra=""):
    t = "\n[[sweep.axis]]\nparameter = %s\nfrom = %s\nto = %s\npoints = %s\n" % (
        tq(parameter) if not parameter.startswith("=") else parameter[1:], frm, to, points)
    if spacing:
        t += "spacing = %s\n" % spacing
    return t + extra


def flagify(args):
    """["--x", "v"] -> ["--x=v"]: a value such as -1 is then not taken for a flag."""
    args, out, i = list(args), [], 0
    while i < len(args):
        if args[i].startswith("--") and i + 1 < len(args) and not args[i + 1].startswith("--"):
            out.append("%s=%s" % (args[i], args[i + 1]))
            i += 2
        else:
            out.append(args[i])
            i += 1
    return out


def flag_needles(flag):
    bare = flag.lstrip("-")
    return [flag, bare.replace("-", "_"), bare]


def same_file(a_rel, b_abs):
    def post(case, res):
        out = case.outputs[0]
        pa = os.path.join(out, a_rel)
        try:
            with open(pa, "rb") as f1, open(b_abs, "rb") as f2:
                if f1.read() != f2.read():
                    return "%s differs from the unsharded %s" % (pa, b_abs)
        except OSError as e:
            return "cannot compare: %s" % e
        return None
    return post


def gen_sweep(quick):
    cat = "sweep"
    K1 = axis("controller.k", "1e4", "1e5", 2)

    def sw(label, text, expect, needles, extra_args=(), runtime=False):
        scen = scenario_file(cat, text, "sw")
        out = fresh("out/sweep")
        add(cat, label, ["sweep", scen, "--out", out] + flagify(extra_args), expect, needles, outputs=[out])

    head = 'analysis = "both"\nduration = 0.2\n'
    sw("baseline tiny grid", sweep_text(), "accept", [])
    for v in ["-1", "nan", "inf", "0", '"abc"', "1e300"]:
        sw("oscillation_threshold = %s" % v, sweep_text(head + "oscillation_threshold = %s\n" % v),
           "either" if v in ("0", "1e300") else "refuse", ["oscillation_threshold"])
    for v in ["-1", "0", "nan", "inf", "1e-300", '"abc"', "1e12"]:
        sw("sweep duration = %s" % v, sweep_text('analysis = "both"\nduration = %s\n' % v),
           "either" if v in ("1e-300",) else "refuse", ["duration", "sweep.duration"])
    for v in ['"nope"', "1", '""', '"Linear"']:
        sw("analysis = %s" % v, sweep_text("analysis = %s\nduration = 0.2\n" % v), "refuse", ["analysis"])
    for v in ['"linear"', '"simulation"']:
        sw("analysis = %s" % v, sweep_text("analysis = %s\nduration = 0.2\n" % v), "accept", [])
    sw("unknown key in [sweep]", sweep_text(head + "resolution = 3\n"), "refuse", ["resolution"])
    sw("unknown key in an axis", sweep_text(head, K1 + "step = 3\n"), "refuse", ["step"])
    sw("duplicated axis", sweep_text(head, K1 + K1), "refuse", ["controller.k", "duplicate", "twice"])
    sw("three axes", sweep_text(head, SWEEP_AXES + axis("platform.velocity", "0.01", "0.02", 2)), "refuse",
       ["axis", "axes", "two"])
    sw("no axis", sweep_text(head, ""), "refuse", ["axis", "axes"])
    sw("no [sweep] table", fig05b(duration="0.2"), "refuse", ["sweep"])
    sw("axis is a table not array", sweep_text(head, "\n[sweep.axis]\nparameter = \"controller.k\"\nfrom = 1\nto = 2\npoints = 2\n"),
       "refuse", ["axis"])
    for par, exp in [("overrides.nope.k_x", "refuse"), ("nope", "refuse"), ("controller.kk", "refuse"),
                     ("overrides.isolator.nope", "refuse"), ("overrides.bearing_friction", "refuse"),
                     ("", "refuse"), ("spread.nope", "refuse"), ("overrides.isolator.k_x", "accept"),
                     ("alpha", "accept"), ("beta", "accept"), ("spread.friction", "either"),
                     ("overrides.table.mass", "accept"), ("OVERRIDES.isolator.k_x", "refuse")]:
        lo, hi = ("1e4", "5e4") if "k_x" in par else ("0.5", "2")
        sw("axis parameter %r" % par, sweep_text(head, axis(par, lo, hi, 2)), exp,
           [par, par.rsplit(".", 1)[0] if par.count(".") > 1 else par] if par else ["parameter"])
    sw("axis parameter is a number", sweep_text(head, axis("=3", "1", "2", 2)), "refuse", ["parameter"])
    sw("axis through negative gains", sweep_text(head, axis("controller.k", "-1e4", "1e4", 3)), "either",
       ["controller.k", "negative", "from"])
    sw("axis of negative damping", sweep_text(head, axis("controller.c", "-300", "-100", 2)), "either",
       ["controller.c", "negative"])
    sw("axis through negative mass", sweep_text(head, axis("overrides.table.mass", "-1", "1", 3)), "refuse",
       ["mass", "overrides.table.mass"])
    sw("axis through zero sigma0", sweep_text(head, axis("overrides.bearing_friction.sigma0", "0", "1e6", 2)),
       "refuse", ["sigma0"])
    sw("axis f_c above f_s", sweep_text(head, axis("overrides.bearing_friction.f_c", "5", "8", 2)), "either",
       ["f_c", "f_s"])  # a point may be refused and reported; a whole-run refusal is also fine
    sw("axis of platform velocity through 0", sweep_text(head, axis("platform.velocity", "-0.02", "0.02", 3)),
       "either", ["platform.velocity"])
    for v, exp in [("0", "refuse"), ("-1", "refuse"), ("1", "either"), ("1000000000000", "refuse"),
                   ("2.5", "refuse"), ('"abc"', "refuse"), ("nan", "refuse")]:
        sw("points = %s" % v, sweep_text(head, axis("controller.k", "1e4", "1e5", v)), exp, ["points"])
    sw("1e6 x 1e6 grid", sweep_text(head, axis("controller.k", "1e4", "1e5", "1000000") +
                                    axis("controller.c", "50", "200", "1000000")), "refuse", ["points", "grid"])
    for lo, hi, sp, exp in [("0", "1e5", '"log"', "refuse"), ("-1e4", "1e5", '"log"', "refuse"),
                            ("-1e5", "-1e4", '"log"', "either"), ("1e4", "1e5", '"nope"', "refuse"),
                            ("1e4", "1e4", '"log"', "either"), ("1e5", "1e4", '"log"', "either"),
                            ("nan", "1e5", '"lin"', "refuse"), ("1e4", "inf", '"lin"', "refuse"),
                            ("1e4", "1e300", '"log"', "either"), ('"a"', "1e5", '"lin"', "refuse")]:
        sw("axis %s..%s spacing %s" % (lo, hi, sp), sweep_text(head, axis("controller.k", lo, hi, 3, sp)), exp,
           ["spacing", "log", "from", "to", "controller.k"])
    base = sweep_text()
    for sh, exp in [("2/2", "refuse"), ("1/0", "refuse"), ("abc", "refuse"), ("0/0", "refuse"),
                    ("-1/2", "refuse"), ("1/2/3", "refuse"), ("0/1", "accept"), ("1/2", "accept"),
                    ("0/1000000", "either"), ("/2", "refuse"), ("0/-1", "refuse"), ("", "refuse"),
                    ("18446744073709551615/18446744073709551616", "refuse")]:
        sw("--shard=%s" % sh, base, exp, ["--shard", "shard"], ["--shard", sh])
    # merging
    S = scenario_file(cat, base, "merge")
    full, A, B = fresh("out/full"), fresh("out/shardA"), fresh("out/shardB")
    setup(["sweep", S, "--out", full])
    setup(["sweep", S, "--out", A, "--shard", "0/2"])
    setup(["sweep", S, "--out", B, "--shard", "1/2"])
    out = fresh("out/merge")
    add(cat, "merge two shards equals unsharded", ["sweep", S, "--merge", A, "--merge", B, "--out", out],
        "accept", [], outputs=[out], post=same_file("points.csv", os.path.join(full, "points.csv")),
        guard=[A, B], guard_always=True)
    out = fresh("out/merge")
    add(cat, "merge one shard twice", ["sweep", S, "--merge", A, "--merge", A, "--out", out], "refuse",
        [os.path.basename(A), "twice", "duplicate", "more than once"], guard=[A], guard_always=True)
    out = fresh("out/merge")
    add(cat, "merge one shard twice plus the other",
        ["sweep", S, "--merge", A, "--merge", A, "--merge", B, "--out", out], "refuse",
        [os.path.basename(A), "twice", "duplicate", "more than once"], guard=[A, B], guard_always=True)
    out = fresh("out/merge")
    add(cat, "merge an incomplete set of shards", ["sweep", S, "--merge", A, "--out", out], "either",
        [os.path.basename(A), "missing", "shard", "incomplete"], outputs=[out], guard=[A], guard_always=True)
    S2 = scenario_file(cat, sweep_text(head, axis("controller.k", "1e4", "1e5", 3) +
                                       axis("controller.c", "50", "200", 2, '"log"')), "other")
    C = fresh("out/shardC")
    setup(["sweep", S2, "--out", C, "--shard", "1/2"])
    out = fresh("out/merge")
    add(cat, "merge shards of different grids", ["sweep", S, "--merge", A, "--merge", C, "--out", out],
        "refuse", ["grid", os.path.basename(C), "differ"], guard=[A, C], guard_always=True)
    out = fresh("out/merge")
    add(cat, "merge shards into another grid's scenario", ["sweep", S2, "--merge", A, "--merge", B,
                                                           "--out", out],
        "refuse", ["grid", "differ", "scenario", os.path.basename(A)], guard=[A, B], guard_always=True)
    Anan = fresh("out/shardNaN")
    shutil.copytree(A, Anan)
    pc = os.path.join(Anan, "points.csv")
    if os.path.exists(pc):
        lines = read(pc).splitlines()
        for i in range(1, len(lines)):
            cells = lines[i].split(",")
            if len(cells) > 5 and cells[5]:
                cells[5] = "NaN"
                cells[4] = "NaN"
                lines[i] = ",".join(cells)
                break
        write(pc, "\n".join(lines) + "\n")
    out = fresh("out/merge")
    add(cat, "merge a shard whose points.csv has a NaN row", ["sweep", S, "--merge", Anan, "--merge", B,
                                                              "--out", out],
        "refuse", ["nan", "points.csv", os.path.basename(Anan)], outputs=[out], guard=[Anan, B],
        guard_always=True)
    Agarb = fresh("out/shardGarbage")
    shutil.copytree(A, Agarb)
    write(os.path.join(Agarb, "points.csv"), "garbage\x00\xff\n", "w")
    out = fresh("out/merge")
    add(cat, "merge a shard whose points.csv is garbage", ["sweep", S, "--merge", Agarb, "--merge", B,
                                                           "--out", out],
        "refuse", ["points.csv", os.path.basename(Agarb)], guard=[Agarb, B], guard_always=True)
    Aprov = fresh("out/shardNoProv")
    shutil.copytree(A, Aprov)
    if os.path.exists(os.path.join(Aprov, "provenance.json")):
        os.remove(os.path.join(Aprov, "provenance.json"))
    out = fresh("out/merge")
    add(cat, "merge a shard without provenance.json", ["sweep", S, "--merge", Aprov, "--merge", B,
                                                       "--out", out],
        "refuse", ["provenance", os.path.basename(Aprov)], guard=[Aprov, B], guard_always=True)
    out = fresh("out/merge")
    add(cat, "merge a missing folder", ["sweep", S, "--merge", os.path.join(SCRATCH, "nope"), "--merge", B,
                                        "--out", out], "refuse", ["nope"])
    add(cat, "merge into one of the shards", ["sweep", S, "--merge", A, "--merge", B, "--out", A], "either",
        [os.path.basename(A)], outputs=[A])
    # resume into another sweep's folder
    D2 = fresh("out/other")
    setup(["sweep", S2, "--out", D2])
    add(cat, "resume into a folder of another sweep", ["sweep", S, "--out", D2], "refuse",
        ["provenance", "differ", "grid", "--force", os.path.basename(D2)], guard=[D2])
    D3 = fresh("out/again")
    setup(["sweep", S, "--out", D3])
    add(cat, "rerun into its own finished folder", ["sweep", S, "--out", D3], "either", [], outputs=[D3],
        post=same_file("points.csv", os.path.join(full, "points.csv")))
    f = write(fresh("out/afile", ".txt"), "precious\n")
    add(cat, "--out pointing at an existing file", ["sweep", S, "--out", f], "refuse",
        ["--out", os.path.basename(f), "not a directory", "exists"], guard=[f], guard_always=True)
    f2 = write(fresh("out/afile", ".txt"), "precious\n")
    add(cat, "--out pointing at an existing file with --force", ["sweep", S, "--out", f2, "--force"], "either",
        ["--out", os.path.basename(f2), "not a directory"], guard=[f2], guard_always=False)
    add(cat, "--out under an existing file", ["sweep", S, "--out", os.path.join(f, "sub")], "refuse",
        ["--out", os.path.basename(f), "not a directory"], guard=[f], guard_always=True)
    # a stale journal of another sweep beside the output folder
    D4 = fresh("out/journal")
    J = os.path.join(os.path.dirname(D4), "." + os.path.basename(D4) + ".journal")
    os.makedirs(J, exist_ok=True)
    write(os.path.join(J, "junk.json"), '{"items": "nope"}')
    add(cat, "stale journal with junk", ["sweep", S, "--out", D4], "either", ["journal"], outputs=[D4],
        guard=[J])


# ---------------------------------------------------------------------------
# 4. robust
# ---------------------------------------------------------------------------

ROBUST_HEAD = '[robust]\nsamples = 8\nseed = 7\nanalysis = "linear"\nsampling = "sobol"\n'


def rparam(parameter, distribution, **kw):
    t = "\n[[robust.parameter]]\nparameter = %s\ndistribution = %s\n" % (
        tq(parameter), tq(distribution) if not distribution.startswith("=") else distribution[1:])
    for k, v in kw.items():
        t += "%s = %s\n" % (k, v)
    return t


def robust_text(head=ROBUST_HEAD, params=None, base=None):
    if params is None:
        params = (rparam("overrides.bearing_friction.f_s", "normal", sd="0.05") +
                  rparam("overrides.isolator.k_x", "uniform", half_width="0.3"))
    return (base or fig05b(duration="0.2")) + "\n" + head + params


def gen_robust(quick):
    cat = "robust"

    def rb(label, text, expect, needles, extra=()):
        scen = scenario_file(cat, text, "rb")
        out = fresh("out/robust")
        add(cat, label, ["robust", scen, "--out", out] + flagify(extra), expect, needles, outputs=[out])

    rb("baseline", robust_text(), "accept", [])
    shipped = read(os.path.join(REPO, "scenarios", "robust", "fig05b_population.toml"))
    shipped = set_line(shipped, "robot", tq(ROBOT1))
    shipped = set_line(shipped, "duration", "0.2")
    rb("shipped fig05b_population, 16 samples", shipped, "accept", [], ["--samples", "16"])
    four = read(os.path.join(REPO, "scenarios", "robust", "four_bearing_population.toml"))
    four = set_line(set_line(four, "robot", tq(ROBOT4)), "duration", "0.5")
    four = set_line(four, "window", "[0.25, 0.5]", "statistics")
    rb("shipped four_bearing_population, 8 samples", four, "accept", [], ["--samples", "8"])
    for an in ("both", "simulation"):
        rb("analysis = %s" % an, robust_text(ROBUST_HEAD.replace('"linear"', tq(an))), "accept", [])
    for sm in ("random", "lhs"):
        rb("sampling = %s" % sm, robust_text(ROBUST_HEAD.replace('"sobol"', tq(sm))), "accept", [])
    heads = {"samples": "8", "seed": "7", "analysis": '"linear"', "sampling": '"sobol"'}
    for key, good in heads.items():
        for lit, _ in TOML_VALUES + [('"nope"', "nope")]:
            if lit == good:
                continue
            h = ROBUST_HEAD.replace("%s = %s" % (key, good), "%s = %s" % (key, lit))
            if key == "seed" and lit in ("0",):
                exp = "accept"
            elif key == "seed" and lit in ("1e300", "1e-300", "-1"):
                exp = "refuse"
            elif key == "samples" and lit in ("1e300", "1e-300"):
                exp = "refuse"
            else:
                exp = "refuse"
            rb("[robust] %s = %s" % (key, lit), robust_text(h), exp, key_needles("robust", key))
        h = ROBUST_HEAD.replace("%s = %s\n" % (key, good), "")
        rb("[robust] %s deleted" % key, robust_text(h), "either", key_needles("robust", key))
    rb("samples = 70000 with sobol", robust_text(ROBUST_HEAD.replace("samples = 8", "samples = 70000")),
       "either", ["samples", "sobol", "65536"])
    rb("samples = 1 with sobol", robust_text(ROBUST_HEAD.replace("samples = 8", "samples = 1")), "either",
       ["samples"])
    rb("samples = 7 (not a power of two) with sobol",
       robust_text(ROBUST_HEAD.replace("samples = 8", "samples = 7")), "either", ["samples", "sobol"])
    rb("samples = 1e12", robust_text(ROBUST_HEAD.replace("samples = 8", "samples = 1000000000000")), "refuse",
       ["samples"])
    rb("unknown key in [robust]", robust_text(ROBUST_HEAD + "confidence = 0.9\n"), "refuse", ["confidence"])
    rb("no [robust] table", fig05b(duration="0.2"), "refuse", ["robust"])
    rb("no parameters", robust_text(params=""), "refuse", ["parameter"])
    P = "overrides.bearing_friction.f_s"
    cases = [
        ("unknown distribution", rparam(P, "cauchy", sd="0.1"), "refuse", ["cauchy", "distribution"]),
        ("distribution is a number", rparam(P, "=3", sd="0.1"), "refuse", ["distribution"]),
        ("normal too wide for a positive parameter", rparam(P, "normal", sd="10"), "refuse",
         [P, "sd", "positive", "wide", "negative"]),
        ("normal sd = 0.5 relative on f_s", rparam(P, "normal", sd="0.5"), "either", [P, "sd"]),
        ("uniform half_width = 2 on f_s", rparam(P, "uniform", half_width="2"), "refuse",
         [P, "half_width", "positive", "negative"]),
        ("uniform half_width = 1 on f_s", rparam(P, "uniform", half_width="1"), "refuse",
         [P, "half_width", "positive", "zero"]),
        ("relative spread of a zero-nominal parameter", rparam("overrides.isolator.k_y", "uniform",
                                                               half_width="0.3"),
         "refuse", ["overrides.isolator.k_y", "zero", "nominal"]),
        ("relative normal of a zero-nominal parameter", rparam("overrides.isolator.c_z", "normal", sd="0.1"),
         "refuse", ["overrides.isolator.c_z", "zero", "nominal"]),
        ("absolute spread of a zero-nominal parameter",
         rparam("overrides.isolator.k_y", "uniform", relative="false", low="0", high="100"), "either",
         ["overrides.isolator.k_y", "relative"]),
        ("pattern matching nothing", rparam("overrides.zzz_*.f_s", "normal", sd="0.1"), "refuse",
         ["overrides.zzz_*.f_s", "zzz", "matches no", "nothing"]),
        ("pattern of a key matching nothing", rparam("overrides.*.nope", "normal", sd="0.1"), "refuse",
         ["overrides.*.nope", "nope"]),
        ("parameter naming nothing", rparam("overrides.nope.f_s", "normal", sd="0.1"), "refuse",
         ["overrides.nope.f_s", "nope"]),
        ("parameter empty", rparam("", "normal", sd="0.1"), "refuse", ["parameter"]),
        ("duplicated parameter", rparam(P, "normal", sd="0.05") + rparam(P, "uniform", half_width="0.1"),
         "refuse", [P, "duplicate", "twice"]),
        ("pattern overlapping a parameter", rparam(P, "normal", sd="0.05") +
         rparam("overrides.bearing_*.f_s", "normal", sd="0.05"), "refuse", [P, "duplicate", "twice", "overlap"]),
        ("truncnormal low > high", rparam(P, "truncnormal", sd="0.1", low="0.2", high="-0.2"), "refuse",
         ["low", "high"]),
        ("truncnormal low == high", rparam(P, "truncnormal", sd="0.1", low="0.1", high="0.1"), "refuse",
         ["low", "high"]),
        ("truncnormal without bounds", rparam(P, "truncnormal", sd="0.1"), "either", ["low", "high"]),
        ("truncnormal window far in the tail", rparam(P, "truncnormal", sd="0.01", low="0.5", high="0.6"),
         "either", ["low", "high", "tail"]),
        ("truncnormal crossing zero (relative low = -2)", rparam(P, "truncnormal", sd="0.1", low="-2", high="0.1"),
         "refuse", ["low", P, "positive"]),
        ("lognormal sd = -1", rparam(P, "lognormal", sd="-1"), "refuse", ["sd"]),
        ("lognormal sd = 50", rparam(P, "lognormal", sd="50"), "either", ["sd", P]),
        ("lognormal with median", rparam(P, "lognormal", sd="0.1", median="6.0", relative="false"), "either",
         ["median"]),
        ("lognormal median = -1 absolute", rparam(P, "lognormal", sd="0.1", median="-1", relative="false"),
         "refuse", ["median"]),
        ("normal without sd", rparam(P, "normal"), "refuse", ["sd"]),
        ("normal with half_width", rparam(P, "normal", half_width="0.1"), "refuse", ["half_width", "sd"]),
        ("uniform without half_width", rparam(P, "uniform"), "either", ["half_width", "low", "high"]),
        ("uniform low > high absolute", rparam(P, "uniform", relative="false", low="7", high="6"), "refuse",
         ["low", "high"]),
        ("absolute uniform below zero", rparam(P, "uniform", relative="false", low="-1", high="6"), "refuse",
         ["low", P, "positive"]),
        ("absolute normal mean = -5", rparam(P, "normal", relative="false", mean="-5", sd="0.1"), "refuse",
         ["mean", P, "positive"]),
        ("relative = \"abc\"", rparam(P, "normal", sd="0.1", relative='"abc"'), "refuse", ["relative"]),
        ("shared = \"abc\"", rparam(P, "normal", sd="0.1", shared='"abc"'), "refuse", ["shared"]),
        ("shared = true on a single element", rparam(P, "normal", sd="0.1", shared="true"), "either", ["shared"]),
        ("unknown key in a parameter", rparam(P, "normal", sd="0.1", spread="0.1"), "refuse", ["spread"]),
        ("f_c above f_s after sampling", rparam("overrides.bearing_friction.f_c", "uniform", half_width="0.5"),
         "either", ["f_c", "f_s", "refused"]),
        ("sigma0 spread", rparam("overrides.bearing_friction.sigma0", "lognormal", sd="0.3"), "accept", []),
        ("controller.k uniform", rparam("controller.k", "uniform", half_width="0.5"), "accept", []),
        ("platform.velocity normal", rparam("platform.velocity", "normal", sd="0.1"), "either",
         ["platform.velocity"]),
    ]
    for k in ("sd", "half_width", "low", "high", "mean", "median"):
        for lit in ("nan", "inf", "-inf", '"abc"', "1e300"):
            dist = {"sd": "normal", "half_width": "uniform", "low": "truncnormal", "high": "truncnormal",
                    "mean": "normal", "median": "lognormal"}[k]
            kw = {"sd": "0.1"} if dist in ("normal", "truncnormal", "lognormal") else {}
            if dist == "uniform":
                kw = {}
            if dist == "truncnormal":
                kw.update(low="-0.2", high="0.2")
            if k in ("mean", "median"):
                kw["relative"] = "false"
            kw[k] = lit
            cases.append(("%s = %s" % (k, lit), rparam(P, dist, **kw),
                          "either" if (k == "high" and lit in ("inf", "1e300")) or
                          (k in ("mean", "median") and lit == "1e300") else "refuse", [k, "spread"]))
    for label, params, exp, needles in cases:
        m = re.search(r'parameter = "([^"]*)"', params)
        rb(label, robust_text(params=params), exp, needles + ([m.group(1)] if m and m.group(1) else []))
    # from_fit: a fit's fit.json drawn jointly; damaged files are named, never drawn.
    def fit_json(paths, values, matrix, extra=None):
        doc = {"covariance": {"parameters": [q.rsplit(".", 1)[-1] for q in paths], "paths": paths,
                              "values": values, "matrix": matrix,
                              "log_matrix": [[v / (values[i] * values[j]) for j, v in enumerate(row)]
                                             for i, row in enumerate(matrix)],
                              "method": "campaign", "degrees_of_freedom": 3},
               "not_identifiable": []}
        doc.update(extra or {})
        return write(fresh("robust/fit", ".json"), json.dumps(doc))

    good_fit = (["overrides.bearing_friction.sigma0", "controller.c"], [2.2e6, 100.0],
                [[1e10, 1e3], [1e3, 25.0]])

    def from_fit(path, draw=None, params=""):
        head = ROBUST_HEAD + "from_fit = %s\n" % tq(path)
        if draw is not None:
            head += "from_fit_draw = %s\n" % draw
        return robust_text(head, params=params)

    rb("from_fit alone", from_fit(fit_json(*good_fit)), "accept", [])
    rb("from_fit with a parameter", from_fit(fit_json(*good_fit), params=rparam(
        "overrides.isolator.k_x", "uniform", half_width="0.3")), "accept", [])
    replicates = {"replicates": [[2.1e6, 95.0], [2.3e6, 104.0], [2.2e6, 99.0], [2.25e6, 101.0]]}
    rb("from_fit replicates", from_fit(fit_json(*good_fit, extra=replicates), '"replicates"'), "accept", [])
    rb("from_fit replicates missing", from_fit(fit_json(*good_fit), '"replicates"'), "refuse",
       ["replicates", "fit"])
    rb("from_fit draw unknown", from_fit(fit_json(*good_fit), '"bootstrap"'), "refuse", ["from_fit_draw"])
    rb("from_fit missing file", from_fit(os.path.join(SCRATCH, "robust", "no_such_fit.json")), "refuse",
       ["no_such_fit.json"])
    rb("from_fit not JSON", from_fit(write(fresh("robust/fit", ".json"), "not json")), "refuse",
       ["from_fit", ".json"])
    rb("from_fit no covariance", from_fit(write(fresh("robust/fit", ".json"), "{}")), "refuse",
       ["covariance"])
    rb("from_fit path naming nothing", from_fit(fit_json(["overrides.nope.sigma0", "controller.c"],
                                                         *good_fit[1:])), "refuse", ["covariance.paths[0]"])
    rb("from_fit matrix 1 x 1 for 2", from_fit(fit_json(good_fit[0], good_fit[1], [[1e10]])), "refuse",
       ["covariance.matrix"])
    rb("from_fit negative eigenvalue", from_fit(fit_json(good_fit[0], good_fit[1], [[1e10, 1e6], [1e6, 25.0]])),
       "refuse", ["negative eigenvalue"])
    rb("from_fit NaN value", from_fit(fit_json(good_fit[0], [float("nan"), 100.0], good_fit[2])), "refuse",
       ["from_fit", "fit"])
    undetermined = {"not_identifiable": [{"parameter": "c", "reason": "no interval"}]}
    rb("from_fit undetermined parameter", from_fit(fit_json(*good_fit, extra=undetermined)), "refuse",
       ["c was not determined"])
    rb("from_fit and the same parameter", from_fit(fit_json(*good_fit), params=rparam(
        "controller.c", "normal", sd="0.1")), "refuse", ["controller.c", "too"])
    for flag, vals in [("--samples", ["0", "-1", "nan", "abc", "1e3", "18446744073709551616"]),
                       ("--seed", ["-1", "nan", "abc", "18446744073709551616"]),
                       ("--threads", ["0", "-1", "abc"]), ("--shard", ["2/2", "1/0", "abc"])]:
        for v in vals:
            rb("%s=%s" % (flag, v), robust_text(), "either" if (flag, v) == ("--threads", "0") else "refuse",
               flag_needles(flag), [flag, v])


# ---------------------------------------------------------------------------
# 5. identify
# ---------------------------------------------------------------------------


def fit_near_truth(truth, tol=0.25):
    """post oracle: the identified values lie near the simulated stage's."""
    def post(case, res):
        try:
            doc = json.loads(res.stdout)
        except ValueError:
            return "--json output is not JSON"
        found = {}

        def walk(o, path=""):
            if isinstance(o, dict):
                for k, v in o.items():
                    if k in truth and isinstance(v, dict) and isinstance(v.get("value"), (int, float)):
                        found.setdefault(k, v["value"])
                    elif k in truth and isinstance(v, (int, float)):
                        found.setdefault(k, v)
                    walk(v, path + "." + k)
            elif isinstance(o, list):
                for v in o:
                    walk(v, path)
        walk(doc)
        for k, t in truth.items():
            if k in found and abs(found[k] - t) > tol * abs(t):
                return "identified %s = %g, the data's true value is %g" % (k, found[k], t)
        return None
    return post


def gen_identify(quick):
    cat = "identify"
    d = os.path.join(SCRATCH, "identify")
    os.makedirs(d, exist_ok=True)
    fss = os.path.join(d, "fss.csv")
    frf = os.path.join(d, "frf.csv")
    setup(["identify", "simulate-stribeck", RIGID, "--out", fss])
    setup(["identify", "simulate-frf", RIGID, "--out", frf])
    truth_s = {"f_c": 5.1, "f_s": 6.5, "v_s": 0.0167, "sigma2": 14.2}
    truth_f = {"sigma0": 2.2e6}
    S = read(fss).splitlines() if os.path.exists(fss) else ["velocity_mm_per_s,force_N", "1,5"]
    Fq = read(frf).splitlines() if os.path.exists(frf) else ["freq_Hz,mag_dB,phase_deg", "10,-120,0"]

    def ident(kind, label, text, expect, needles, extra=(), post=None, binary=False):
        path = fresh("identify/%s" % kind, ".csv")
        write(path, text, "wb" if binary else "w")
        out = fresh("out/ident")
        add(cat, "%s: %s" % (kind, label), ["identify", kind, path, "--json", "--out", out] + flagify(extra),
            expect, needles + [os.path.basename(path)] * 0, outputs=[out], json_stdout=True, post=post)
        return path

    def rows(lines, f):
        return "\n".join([lines[0]] + [f(l) for l in lines[1:]]) + "\n"

    for kind, L, truth in (("stribeck", S, truth_s), ("frf", Fq, truth_f)):
        head = L[0].split(",")
        fn = os.path.basename
        ident(kind, "shipped simulated data", "\n".join(L) + "\n", "accept", [], post=fit_near_truth(truth))
        ident(kind, "empty file", "", "refuse", ["empty", "header", "no data", "line 1"])
        ident(kind, "header only", L[0] + "\n", "refuse", ["no data", "rows", "empty", "not identifiable"])
        ident(kind, "one row", L[0] + "\n" + L[1] + "\n", "refuse", ["not identifiable", "rows", "points"])
        ident(kind, "two rows", "\n".join(L[:3]) + "\n", "refuse", ["not identifiable", "rows", "points"])
        for tok in ("NaN", "inf", "-inf", "", "abc", "1e400", "0x10"):
            L2 = list(L)
            c = L2[3].split(",")
            c[1] = tok
            L2[3] = ",".join(c)
            ident(kind, "cell %r in column %s" % (tok, head[1]), "\n".join(L2) + "\n", "refuse",
                  [head[1], "line 4", "column 2"])
            L2 = list(L)
            c = L2[3].split(",")
            c[0] = tok
            L2[3] = ",".join(c)
            ident(kind, "cell %r in column %s" % (tok, head[0]), "\n".join(L2) + "\n", "refuse",
                  [head[0], "line 4", "column 1"])
        for i, h in enumerate(head):
            txt = "\n".join(",".join(x for j, x in enumerate(l.split(",")) if j != i) for l in L) + "\n"
            ident(kind, "column %s missing" % h, txt, "either" if (kind == "frf" and "phase" in h) else "refuse",
                  [h, "column", "missing"])
        for i, h in enumerate(head):
            bad = re.sub(r"_[A-Za-z_]+$", "_furlongs", h) if "_" in h else h + "_furlongs"
            txt = "\n".join([",".join(bad if j == i else x for j, x in enumerate(head))] + L[1:]) + "\n"
            ident(kind, "unknown unit suffix %s" % bad, txt, "refuse", [bad, "unit", "furlongs"])
        txt = "\n".join([",".join(x.split("_")[0] for x in head)] + L[1:]) + "\n"
        ident(kind, "unitless columns without unit flags", txt, "refuse", ["unit", head[0].split("_")[0]])
        ident(kind, "duplicate column", "\n".join([L[0] + "," + head[1]] + [l + "," + l.split(",")[1]
                                                                           for l in L[1:]]) + "\n",
              "refuse", [head[1], "duplicate", "twice"])
        ident(kind, "extra unknown column", "\n".join([L[0] + ",temperature_C"] + [l + ",20" for l in L[1:]]) + "\n",
              "either", ["temperature_C"])
        ident(kind, "short row", "\n".join(L[:4] + [L[4].split(",")[0]] + L[5:]) + "\n", "refuse",
              ["line 5", "column", "fields"])
        ident(kind, "long row", "\n".join(L[:4] + [L[4] + ",1"] + L[5:]) + "\n", "refuse",
              ["line 5", "column", "fields"])
        ident(kind, "decimal commas with comma delimiter",
              "\n".join([L[0]] + [l.replace(".", ",") for l in L[1:]]) + "\n", "refuse",
              ["line 2", "decimal", "column", "fields"])
        ident(kind, "decimal commas with semicolons",
              "\n".join([L[0].replace(",", ";")] + [l.replace(",", ";").replace(".", ",") for l in L[1:]]) + "\n",
              "accept", [], post=fit_near_truth(truth))
        ident(kind, "tab delimited", "\n".join(l.replace(",", "\t") for l in L) + "\n", "accept", [],
              post=fit_near_truth(truth))
        ident(kind, "mixed delimiters", "\n".join([L[0]] + [l.replace(",", ";") if i % 2 else l
                                                          for i, l in enumerate(L[1:])]) + "\n", "refuse",
              ["line 2", "line 3", "delimiter", "column"])
        ident(kind, "header with ; rows with ,", "\n".join([L[0].replace(",", ";")] + L[1:]) + "\n", "refuse",
              ["line 2", "delimiter", "column", "fields"])
        ident(kind, "comments and blank lines", "# lab 3\n\n" + "\n".join(L[:5]) + "\n# mid\n\n" +
              "\n".join(L[5:]) + "\n", "accept", [], post=fit_near_truth(truth))
        ident(kind, "CRLF and BOM", "\ufeff" + "\r\n".join(L) + "\r\n", "accept", [], post=fit_near_truth(truth))
        ident(kind, "binary garbage", bytes(range(256)) * 4, "refuse", ["utf", "line", "header", "column"],
              binary=True)
        ident(kind, "quoted header", "\n".join([",".join('"%s"' % h for h in head)] + L[1:]) + "\n", "either",
              [head[0]])
        ident(kind, "all data rows identical", "\n".join([L[0]] + [L[len(L) // 2]] * 20) + "\n", "refuse",
              ["not identifiable", head[0]])
    # stribeck specific
    one_speed = [S[0]] + [l for l in S[1:] if abs(float(l.split(",")[0]) - float(S[1].split(",")[0])) < 1e-12]
    neg = S[1].split(",")
    one_speed = [S[0]] + [S[1], "%r,%r" % (-float(neg[0]), -float(neg[1]))] * 5
    ident("stribeck", "data at one speed only", "\n".join(one_speed) + "\n", "refuse", ["not identifiable"])
    ident("stribeck", "data at one speed only, --allow-undetermined", "\n".join(one_speed) + "\n", "either",
          ["not identifiable"], ["--allow-undetermined"])
    two = [S[0]] + [l for l in S[1:] if abs(float(l.split(",")[0])) > 100]
    ident("stribeck", "only fast speeds (no Stribeck region)", "\n".join(two) + "\n", "refuse",
          ["not identifiable"])
    ident("stribeck", "only fast speeds, --allow-undetermined", "\n".join(two) + "\n", "either",
          ["not identifiable"], ["--allow-undetermined"])
    ident("stribeck", "all-zero forces", rows(S, lambda l: l.split(",")[0] + ",0"), "refuse",
          ["not identifiable", "force", "zero"])
    ident("stribeck", "forces scaled by 1e300", rows(S, lambda l: "%s,%r" % (l.split(",")[0],
                                                                            float(l.split(",")[1]) * 1e300)),
          "either", ["force", "not identifiable", "range", "large"])
    ident("stribeck", "forces scaled by 1e-300", rows(S, lambda l: "%s,%r" % (l.split(",")[0],
                                                                             float(l.split(",")[1]) * 1e-300)),
          "either", ["force", "not identifiable", "small"])
    ident("stribeck", "velocities all zero", rows(S, lambda l: "0," + l.split(",")[1]), "refuse",
          ["not identifiable", "velocity", "zero"])
    ident("stribeck", "force sign opposite to velocity", rows(S, lambda l: "%s,%r" % (
        l.split(",")[0], -float(l.split(",")[1]))), "refuse", ["not identifiable", "force", "sign", "negative"])
    pos = [S[0]] + [l for l in S[1:] if float(l.split(",")[0]) > 0]
    ident("stribeck", "one velocity sign without --one-sided", "\n".join(pos) + "\n", "either",
          ["--one-sided", "sign", "one-sided"], post=fit_near_truth(truth_s))
    ident("stribeck", "one velocity sign with --asymmetric", "\n".join(pos) + "\n", "refuse",
          ["--asymmetric", "sign", "not identifiable", "both"], ["--asymmetric", "--one-sided"])
    ident("stribeck", "noisy outliers --robust", rows(S, lambda l: l if hash(l) % 7 else "%s,%r" % (
        l.split(",")[0], float(l.split(",")[1]) * 5)), "either", [], ["--robust"])
    ident("stribeck", "velocity unit mm/s in brackets", "\n".join(["velocity [mm/s],force [N]"] + S[1:]) + "\n",
          "accept", [], post=fit_near_truth(truth_s))
    ident("stribeck", "velocity unit [furlong/fortnight]",
          "\n".join(["velocity [furlong/fortnight],force [N]"] + S[1:]) + "\n", "refuse",
          ["furlong", "unit"])
    # frf specific
    ident("frf", "single frequency", "\n".join([Fq[0]] + [Fq[len(Fq) // 2]] * 10) + "\n", "refuse",
          ["not identifiable"])
    ident("frf", "zero frequency row", "\n".join(Fq[:3] + ["0,-120,0"] + Fq[3:]) + "\n", "refuse",
          ["freq", "line 4", "zero", "positive"])
    ident("frf", "negative frequency row", "\n".join(Fq[:3] + ["-10,-120,0"] + Fq[3:]) + "\n", "refuse",
          ["freq", "line 4", "negative", "positive"])
    ident("frf", "magnitude +1e300 dB", rows(Fq, lambda l: ",".join([l.split(",")[0], "1e300"] + l.split(",")[2:])),
          "refuse", ["mag", "not identifiable", "line 2"])
    ident("frf", "magnitude -1e300 dB (zero response)",
          rows(Fq, lambda l: ",".join([l.split(",")[0], "-1e300"] + l.split(",")[2:])),
          "refuse", ["mag", "not identifiable", "line 2", "zero"])
    ident("frf", "magnitude in m/N all zero",
          "\n".join(["freq_Hz,mag_m_per_N"] + ["%s,0" % l.split(",")[0] for l in Fq[1:]]) + "\n", "refuse",
          ["mag", "not identifiable", "zero"])
    ident("frf", "negative magnitude in m/N",
          "\n".join(["freq_Hz,mag_m_per_N"] + ["%s,-1e-6" % l.split(",")[0] for l in Fq[1:]]) + "\n", "refuse",
          ["mag", "negative", "line 2"])
    ident("frf", "phase without magnitude", "\n".join(",".join([l.split(",")[0], l.split(",")[2]]) for l in Fq) + "\n",
          "refuse", ["mag", "magnitude", "column"])
    ident("frf", "re and im columns zero",
          "\n".join(["freq_Hz,re_G_m_per_N,im_G_m_per_N"] + ["%s,0,0" % l.split(",")[0] for l in Fq[1:]]) + "\n",
          "refuse", ["not identifiable", "zero", "re_G", "im_G"])
    for flag, v, exp in [("--mass", "-1", "refuse"), ("--mass", "nan", "refuse"), ("--mass", "0", "refuse"),
                         ("--mass", "inf", "refuse"), ("--mass", "1e300", "either"),
                         ("--sigma2", "-1", "refuse"), ("--sigma2", "nan", "refuse"),
                         ("--sigma2", "1e9", "either"),
                         ("--sigma2-ci95", "5,1", "refuse"), ("--sigma2-ci95", "nan,1", "refuse"),
                         ("--sigma2-ci95", "abc", "refuse"),
                         ("--sigma2-from", os.path.join(SCRATCH, "nope.json"), "refuse"),
                         ("--sigma2-from", fss, "refuse"),
                         ("--freq-unit", "furlong", "refuse"), ("--mag-unit", "dBm", "refuse"),
                         ("--phase-unit", "grad", "refuse"), ("--element", "", "either"),
                         ("--element", "a,b", "either"), ("--element", "a]\n[b", "either")]:
        ident("frf", "%s=%r" % (flag, v), "\n".join(Fq) + "\n", exp,
              flag_needles(flag) + (["not identifiable"] if exp == "either" else []) +
              ([os.path.basename(v)] if "/" in v else []), [flag, v])
    for flag, v, exp in [("--huber-delta", "-1", "refuse"), ("--huber-delta", "nan", "refuse"),
                         ("--huber-delta", "0", "refuse"), ("--v-s-start", "-1", "refuse"),
                         ("--v-s-start", "nan", "refuse"), ("--v-s-start", "0", "refuse"),
                         ("--v-s-start", "1e300", "either"),
                         ("--loss", "l3", "refuse"), ("--velocity-unit", "furlong", "refuse"),
                         ("--force-unit", "kgf", "refuse"), ("--element", "", "either"),
                         ("--element", 'a"b', "either"), ("--element", "a b", "either")]:
        ident("stribeck", "%s=%r" % (flag, v), "\n".join(S) + "\n", exp, flag_needles(flag), [flag, v])
    # a fit.json from stribeck that is hostile for --sigma2-from
    bad_fit = write(os.path.join(d, "badfit.json"), '{"sigma2": {"value": NaN, "ci95": [1, 2]}}')
    ident("frf", "--sigma2-from a fit.json with NaN", "\n".join(Fq) + "\n", "refuse",
          ["--sigma2-from", "sigma2", "badfit.json"], ["--sigma2-from", bad_fit])
    add(cat, "stribeck: missing file", ["identify", "stribeck", os.path.join(SCRATCH, "nope.csv")], "refuse",
        ["nope.csv"])
    add(cat, "stribeck: a folder", ["identify", "stribeck", SCRATCH], "refuse", [os.path.basename(SCRATCH)])
    add(cat, "stribeck: /dev/null", ["identify", "stribeck", "/dev/null"], "refuse", ["/dev/null", "empty"])
    for sub, extra in [("simulate-stribeck", []), ("simulate-frf", [])]:
        out = fresh("identify/sim", ".csv")
        add(cat, "%s: missing robot" % sub, ["identify", sub, os.path.join(SCRATCH, "nope.urdf"), "--out", out],
            "refuse", ["nope.urdf"])
        add(cat, "%s: scenario file" % sub, ["identify", sub, os.path.join(REPO, "scenarios", "paper",
                                                                            "fig05b_fi.toml"), "--out", out],
            "either", ["steady state"], outputs=[out])
        add(cat, "%s: 4-bearing robot" % sub, ["identify", sub, ROBOT4, "--out", fresh("identify/sim", ".csv")],
            "either", ["friction", "element", "bearing"])

# ---------------------------------------------------------------------------
# 6. modes
# ---------------------------------------------------------------------------


# the keys the modes variants change: a refusal naming one of them is clear
MODES_KEYS = ["controller.k", "controller.c", "controller.k_i", "overrides.bearing_friction.",
              "overrides.isolator.", "overrides.friction_fl.", "mass", "platform.velocity"]


def gen_modes(quick):
    cat = "modes"
    b = fig05b()
    robot_text = read(ROBOT1)
    heavy = write(fresh("modes/heavy", ".urdf"), robot_text.replace('<mass value="1.0"/>', '<mass value="1e9"/>'))
    light = write(fresh("modes/light", ".urdf"), robot_text.replace('<mass value="1.0"/>', '<mass value="1e-9"/>')
                  .replace('<mass value="0.5"/>', '<mass value="1e-9"/>'))
    heavyb = write(fresh("modes/heavyb", ".urdf"), robot_text.replace('<mass value="0.5"/>', '<mass value="1e9"/>'))
    variants = [
        ("baseline fig05b_fi", b),
        ("k = 1e12", set_line(b, "k", "1e12", "controller")),
        ("c = 1e12", set_line(b, "c", "1e12", "controller")),
        ("k_i = 1e12", set_line(b, "k_i", "1e12", "controller")),
        ("k = c = k_i = 1e12", set_line(set_line(set_line(b, "k", "1e12", "controller"), "c", "1e12",
                                                 "controller"), "k_i", "1e12", "controller")),
        ("k = 1e-12, c = 0", set_line(set_line(b, "k", "1e-12", "controller"), "c", "0", "controller")),
        ("k = 0, c = 0", set_line(set_line(b, "k", "0", "controller"), "c", "0", "controller")),
        ("c = -100 (negative damping)", set_line(b, "c", "-100", "controller")),
        ("k = -6e4", set_line(b, "k", "-6e4", "controller")),
        ("table mass 1e9", set_line(b, "robot", tq(heavy))),
        ("bearing mass 1e9", set_line(b, "robot", tq(heavyb))),
        ("masses 1e-9", set_line(b, "robot", tq(light))),
        ("sigma0 = 1e15", b + "\n[overrides.bearing_friction]\nsigma0 = 1e15\n"),
        ("sigma0 = 1e15, c = 1e12", set_line(b, "c", "1e12", "controller") +
         "\n[overrides.bearing_friction]\nsigma0 = 1e15\n"),
        ("sigma0 = 1e-3", b + "\n[overrides.bearing_friction]\nsigma0 = 1e-3\n"),
        ("v_s = 1e-12", b + "\n[overrides.bearing_friction]\nv_s = 1e-12\n"),
        ("isolator k_x = 1e15", b + "\n[overrides.isolator]\nk_x = 1e15\n"),
        ("isolator k_x = 0", b + "\n[overrides.isolator]\nk_x = 0\n"),
        ("isolator k_x = -4e4", b + "\n[overrides.isolator]\nk_x = -4e4\n"),
        ("platform velocity 0", set_line(b, "velocity", "0.0", "platform")),
        ("platform velocity 1e3", set_line(b, "velocity", "1e3", "platform")),
        ("platform velocity 1e-300", set_line(b, "velocity", "1e-300", "platform")),
        ("4-bearing traverse", traverse()),
        ("4-bearing traverse, k = 1e12", set_line(traverse(), "k", "1e12", "controller")),
        ("4-bearing, friction sigma0 = 1e15", traverse() + "\n[overrides.friction_fl]\nsigma0 = 1e15\n"),
        ("rigid stage k_i = 1e12", set_line(set_line(b, "robot", tq(RIGID)), "k_i", "1e12", "controller")),
        ("rigid stage c = 1e12", set_line(set_line(b, "robot", tq(RIGID)), "c", "1e12", "controller")),
    ]
    for label, text in variants:
        scen = scenario_file(cat, text, "m")
        for eq in ("both",) if quick else ("both", "sticking", "slipping"):
            out = fresh("out/modes")
            add(cat, "%s, --equilibrium %s" % (label, eq),
                ["modes", scen, "--json", "--equilibrium", eq, "--out", out], "either",
                ["undetermined", "equilibrium", "singular", "not finite"] + MODES_KEYS, outputs=[out],
                json_stdout=True)
        if not quick:
            out = fresh("out/modes")
            add(cat, "%s, table output" % label, ["modes", scen, "--out", out, "--shapes", "3"], "either",
                ["undetermined", "equilibrium", "singular"] + MODES_KEYS, outputs=[out])


# ---------------------------------------------------------------------------
# 7. flags
# ---------------------------------------------------------------------------


def gen_flags(quick):
    cat = "flags"
    S = scenario_file(cat, fig05b(duration="0.2"), "f")
    SW = scenario_file(cat, sweep_text(), "fsw")
    RB = scenario_file(cat, robust_text(), "frb")
    afile = write(fresh("flags/existing", ".txt"), "precious\n")
    fss = os.path.join(SCRATCH, "flags", "fss.csv")
    setup(["identify", "simulate-stribeck", RIGID, "--out", fss])
    subs = {
        "run": [S, "--no-plots"], "check": [S], "bench": ["--scenario", S, "--rtol", "1e-6", "--repeat", "1"],
        "modes": [S], "sweep": [SW], "robust": [RB], "lyapunov": [S, "--transient", "0.1", "--duration", "0.2"],
        "identify": ["stribeck", fss], "fmu": [S],
    }
    outflag = {"run": "--out", "modes": "--out", "sweep": "--out", "robust": "--out", "fmu": "-o",
               "identify": "--out"}
    for sub, good in subs.items():
        def o():
            if sub in outflag:
                return [outflag[sub], fresh("out/flags")] if sub != "fmu" else ["-o", fresh("out/flags", ".fmu")]
            return []
        add(cat, "%s --help" % sub, [sub, "--help"], "accept", [])
        add(cat, "%s --nope" % sub, [sub] + good + ["--nope"] + o(), "refuse", ["--nope"])
        add(cat, "%s -Z" % sub, [sub] + good + ["-Z"], "refuse", ["-Z"])
        add(cat, "%s without arguments" % sub, [sub], "either" if sub == "bench" else "refuse",
                ["required", "<SCENARIO>", "usage", "<COMMAND>", "<DATA>"])
        add(cat, "%s with a missing scenario" % sub, [sub, os.path.join(SCRATCH, "missing.toml")] +
            (good[1:] if sub not in ("identify", "bench") else []),
            "either" if sub == "bench" else "refuse", ["missing.toml", "<COMMAND>", "unrecognized", "unexpected"])
        add(cat, "%s with an extra positional" % sub, [sub] + good + ["extra_positional"], "refuse",
            ["extra_positional"])
        if sub in outflag:
            f = outflag[sub]
            add(cat, "%s %s without value" % (sub, f), [sub] + good + [f], "refuse", [f, "value"])
            if sub == "fmu":  # -o names a file: replacing it is the documented job
                add(cat, "%s %s at an existing file" % (sub, f), [sub] + good + [f, write(fresh("flags/keep", ".txt"),
                                                                                           "precious\n")],
                    "either", [f, "exists"])
            else:
                add(cat, "%s %s at an existing file" % (sub, f), [sub] + good + [f, afile], "refuse",
                    [f, os.path.basename(afile), "exists", "not a directory"], guard=[afile], guard_always=True)
            add(cat, "%s %s empty" % (sub, f), [sub] + good + ["%s=" % f if f.startswith("--") else f, ""],
                "refuse", [f, "empty", "value"])
    numeric = [
        ("run", [S, "--no-plots", "--out"], "--rtol", ["-1", "nan", "0", "inf", "abc", "1", "1e-300"]),
        ("run", [S, "--no-plots", "--engine", "rapier", "--out"], "--dt", ["-1", "nan", "0", "inf", "1e-300", "abc"]),
        ("run", [S, "--no-plots", "--out"], "--engine", ["nope", "", "NATIVE"]),
        ("modes", [S, "--out"], "--shapes", ["-1", "nan", "abc", "1000000000", "18446744073709551616"]),
        ("modes", [S, "--out"], "--equilibrium", ["nope", ""]),
        ("sweep", [SW, "--out"], "--threads", ["0", "-1", "nan", "abc", "1000000000000"]),
        ("sweep", [SW, "--out"], "--shard", ["2/2", "1/0", "abc", "-1/2"]),
        ("robust", [RB, "--out"], "--threads", ["0", "-1", "abc"]),
        ("robust", [RB, "--out"], "--samples", ["0", "-1", "nan", "1e12"]),
        ("lyapunov", [S, "--transient", "0.1", "--duration", "0.2", "--out-unused"], "--interval",
         ["0", "-1", "nan", "inf", "1e12", "1e-300"]),
        ("lyapunov", [S, "--duration", "0.2", "--out-unused"], "--transient", ["-1", "nan", "inf", "1e12"]),
        ("lyapunov", [S, "--transient", "0.1", "--out-unused"], "--duration", ["-1", "nan", "0", "inf", "1e12"]),
        ("bench", ["--scenario", S, "--repeat", "1", "--out-unused"], "--rtol", ["-1", "nan", "0", "abc", "1e-6,nan"]),
        ("bench", ["--scenario", S, "--rtol", "1e-6", "--out-unused"], "--repeat", ["0", "-1", "abc"]),
        ("bench", ["--scenario", S, "--rtol", "1e-6", "--repeat", "1", "--out-unused"], "--signal",
         ["nope", "", "encoder.jerk"]),
        ("fmu", [S, "-o"], "--library", [os.path.join(SCRATCH, "nope.so"), afile, "/dev/null"]),
    ]
    expect_ok = {("sweep", "--threads", "0"), ("robust", "--threads", "0"), ("run", "--rtol", "1"),
                 ("modes", "--shapes", "1000000000"), ("lyapunov", "--interval", "1e12"),
                 ("lyapunov", "--transient", "1e12"), ("lyapunov", "--duration", "1e12")}
    for sub, pre, flag, vals in numeric:
        for v in vals:
            args = [sub] + [a for a in pre if a not in ("--out", "-o", "--out-unused")]
            outputs = []
            if pre[-1] in ("--out", "-o"):
                out = fresh("out/flags", ".fmu" if sub == "fmu" else "")
                args += [pre[-1], out]
                outputs = [out] if sub != "fmu" else []
            args.append("%s=%s" % (flag, v))
            exp = "either" if (sub, flag, v) in expect_ok else "refuse"
            if (sub, flag, v) == ("lyapunov", "--duration", "1e12"):
                exp = "refuse"
            add(cat, "%s %s=%s" % (sub, flag, v), args, exp, flag_needles(flag) + ([v] if len(v) > 2 else []),
                outputs=outputs)
    add(cat, "unknown subcommand", ["nope"], "refuse", ["nope"])
    add(cat, "no subcommand", [], "refuse", ["usage", "<COMMAND>"])
    add(cat, "--version", ["--version"], "accept", [])
    add(cat, "identify unknown method", ["identify", "nope", fss], "refuse", ["nope"])
    add(cat, "identify frf on stribeck data", ["identify", "frf", fss], "refuse", ["freq", "column", "fss.csv"])
    add(cat, "non-UTF-8 argument", ["check", b"\xff\xfe.toml".decode("utf-8", "surrogateescape")], "refuse",
        ["utf", ".toml", "\ufffd"])


# ---------------------------------------------------------------------------
# 8. output folders
# ---------------------------------------------------------------------------


def no_stale_plots(case, res):
    out = case.outputs[0]
    stale = [f for f in os.listdir(out) if f.endswith((".svg", ".png"))]
    return ("stale plot files remain after --force --no-plots: %s" % ", ".join(sorted(stale))) if stale else None


def foreign_survives(path):
    def post(case, res):
        return None if os.path.exists(path) else "an unrelated file %s was deleted" % path
    return post


def gen_output(quick):
    cat = "output"
    S = scenario_file(cat, fig05b(duration="0.2"), "o")
    S2 = scenario_file(cat, set_line(fig05b(duration="0.2"), "k", "7e4", "controller"), "o2")
    BAD = scenario_file(cat, set_line(fig05b(duration="0.2"), "duration", "nan"), "bad")
    BADRUN = scenario_file(cat, fig05b(duration="0.2") + "\n[overrides.bearing_friction]\nsigma0 = 1e300\n", "badrun")
    SW = scenario_file(cat, sweep_text(), "osw")
    RB = scenario_file(cat, robust_text(), "orb")

    def prepared(args):
        d = fresh("out/prev")
        setup(args + [d])
        return d

    # run
    d = prepared(["run", S, "--out"])
    add(cat, "run into an earlier result without --force", ["run", S, "--out", d], "refuse",
        ["--force", os.path.basename(d), "exists", "earlier"], guard=[d])
    d = prepared(["run", S, "--out"])
    add(cat, "run of another scenario into an earlier result", ["run", S2, "--out", d, "--no-plots"], "refuse",
        ["--force", os.path.basename(d), "exists", "earlier"], guard=[d])
    d = prepared(["run", S, "--out"])
    add(cat, "run --force --no-plots over a result with plots", ["run", S, "--out", d, "--force", "--no-plots"],
        "accept", [], outputs=[d], post=no_stale_plots)
    d = prepared(["run", S, "--out"])
    add(cat, "failing (load) run with --force", ["run", BAD, "--out", d, "--force"], "refuse",
        ["duration"], guard=[d])
    d = prepared(["run", S, "--out"])
    add(cat, "failing (simulation) run with --force", ["run", BADRUN, "--out", d, "--force"], "either",
        ["sigma0", "simulation"], guard=[d], outputs=[d])
    d = prepared(["run", S, "--out"])
    add(cat, "failing (unknown engine flag) run with --force", ["run", S, "--out", d, "--force", "--engine=nope"],
        "refuse", ["nope", "engine"], guard=[d])
    d = fresh("out/foreign")
    os.makedirs(d)
    write(os.path.join(d, "notes.txt"), "mine\n")
    add(cat, "run into a folder with unrelated files", ["run", S, "--out", d, "--no-plots"], "either",
        ["--force", "notes.txt", os.path.basename(d)], guard=[d], outputs=[d],
        post=foreign_survives(os.path.join(d, "notes.txt")))
    d = fresh("out/empty")
    os.makedirs(d)
    add(cat, "run into an existing empty folder", ["run", S, "--out", d, "--no-plots"], "accept", [], outputs=[d])
    d = fresh("out/ro")
    os.makedirs(d)
    os.chmod(d, 0o500)
    add(cat, "run into a read-only folder", ["run", S, "--out", os.path.join(d, "sub"), "--no-plots"],
        "either" if os.geteuid() == 0 else "refuse",  # root writes anyway
        ["permission", "sub", os.path.basename(d)], guard=[d], outputs=[os.path.join(d, "sub")])
    d = prepared(["run", S, "--out"])
    write(os.path.join(d, "trajectory.csv"), "tampered\n")
    add(cat, "run into a result whose trajectory was edited, no --force", ["run", S, "--out", d], "refuse",
        ["--force", os.path.basename(d)], guard=[d])
    d = fresh("out/link")
    target = fresh("out/linktarget")
    os.makedirs(target)
    write(os.path.join(target, "keep.txt"), "keep\n")
    os.symlink(target, d)
    add(cat, "run --force into a symlink to a folder with files", ["run", S, "--out", d, "--force", "--no-plots"],
        "either", ["symlink", os.path.basename(d)], post=foreign_survives(os.path.join(target, "keep.txt")))
    # modes
    d = prepared(["modes", S, "--out"])
    add(cat, "modes into an earlier result without --force", ["modes", S, "--out", d], "refuse",
        ["--force", os.path.basename(d)], guard=[d])
    d = prepared(["modes", S, "--out"])
    add(cat, "failing modes with --force", ["modes", BAD, "--out", d, "--force"], "refuse", ["duration"], guard=[d])
    d = prepared(["modes", S, "--out"])
    add(cat, "modes --force --shapes 0 over one with pictures", ["modes", S, "--out", d, "--force", "--shapes", "0"],
        "either", ["shapes"], outputs=[d], post=no_stale_plots)
    # sweep
    d = prepared(["sweep", SW, "--out"])
    add(cat, "failing sweep with --force over a result", ["sweep", BAD, "--out", d, "--force"], "refuse",
        ["duration", "sweep"], guard=[d])
    d = prepared(["run", S, "--out"])
    add(cat, "sweep into a run's result without --force", ["sweep", SW, "--out", d], "refuse",
        ["--force", os.path.basename(d), "other work"], guard=[d])
    # robust
    d = prepared(["robust", RB, "--out"])
    add(cat, "failing robust with --force over a result", ["robust", BAD, "--out", d, "--force"], "refuse",
        ["duration"], guard=[d])
    d = prepared(["robust", RB, "--out"])
    add(cat, "robust of other samples into a result", ["robust", RB, "--out", d, "--samples", "4"], "either",
        ["--force", "samples", os.path.basename(d)], guard=[d], outputs=[d])
    # identify
    fss = fresh("output/fss", ".csv")
    setup(["identify", "simulate-stribeck", RIGID, "--out", fss])
    d = prepared(["identify", "stribeck", fss, "--out"])
    add(cat, "identify into an earlier result without --force", ["identify", "stribeck", fss, "--out", d], "refuse",
        ["--force", os.path.basename(d)], guard=[d])
    empty = write(fresh("output/empty", ".csv"), "")
    d = prepared(["identify", "stribeck", fss, "--out"])
    add(cat, "failing identify with --force", ["identify", "stribeck", empty, "--out", d, "--force"], "refuse",
        [os.path.basename(empty), "empty"], guard=[d])
    d = prepared(["identify", "stribeck", fss, "--out"])
    und = write(fresh("output/und", ".csv"), "velocity_mm_per_s,force_N\n" + "10,6\n-10,-6\n" * 5)
    add(cat, "undetermined identify with --force", ["identify", "stribeck", und, "--out", d, "--force"], "refuse",
        ["not identifiable"], guard=[d])
    # simulate-stribeck --out at an existing file
    f = write(fresh("output/keep", ".csv"), "keep\n")
    add(cat, "simulate-stribeck over an existing csv", ["identify", "simulate-stribeck", RIGID, "--out", f],
        "either", ["--force", "exists", os.path.basename(f)], outputs=[f])
    # fmu over an existing file
    f = write(fresh("output/keep", ".fmu"), "keep\n")
    add(cat, "fmu -o over an existing file", ["fmu", S, "-o", f], "either", ["exists", "--force", os.path.basename(f)])

def journal_damages(lines):
    """(label, journal text) pairs: the whole run's table cut and damaged as a
    killed run, a full disk or a hand edit leaves it."""
    head, rows = lines[0], lines[1:]
    cut_cell = rows[2].rsplit(",", 1)[0] + "," + rows[2].rsplit(",", 1)[1][:2]
    damaged_verdict = rows[1].replace(",true,", ",tru,", 1).replace(",false,", ",fals,", 1)
    nan_cell = rows[1].rsplit(",", 1)[0] + ",NaN"
    return [
        ("last row cut in its last cell", "\n".join([head, rows[0], rows[1], cut_cell])),
        ("last row cut after its last cell", "\n".join([head, rows[0], rows[1]])),
        ("a verdict damaged inside a whole line", "\n".join([head, rows[0], damaged_verdict, rows[2]]) + "\n"),
        ("a NaN written into a row", "\n".join([head, rows[0], nan_cell]) + "\n"),
        ("the header cut", head[: len(head) // 2]),
        ("an empty journal", ""),
        ("binary junk after whole rows", "\n".join([head, rows[0]]) + "\n\x00\xff\x01garbage"),
        ("a row twice", "\n".join([head, rows[0], rows[0], rows[1]]) + "\n"),
        ("a row of another grid", "\n".join([head, "1.5e4" + rows[0][rows[0].index(","):]]) + "\n"),
        ("windows line ends", "\r\n".join([head, rows[0], rows[1]]) + "\r\n"),
    ]


def gen_journal(quick):
    """A killed study resumed from a damaged journal gives the whole run's
    table byte for byte (damaged rows computed again), or a clear error."""
    cat = "journal"
    studies = [("sweep", scenario_file(cat, sweep_text(), "jsw"), "points", [])]
    studies.append(("robust", scenario_file(cat, robust_text(), "jrb"), "samples", ["--samples", "8"]))
    for command, scen, table, extra in studies:
        whole = fresh("out/whole")
        setup([command, scen, "--out", whole, "--threads", "1"] + extra)
        try:
            lines = read(os.path.join(whole, table + ".csv")).splitlines()
        except OSError:
            continue
        if len(lines) < 4:
            continue
        damages = journal_damages(lines)
        for label, text in damages[:4] if quick else damages:
            out = fresh("out/killed")
            journal = os.path.join(os.path.dirname(out), "." + os.path.basename(out) + ".journal")
            write(os.path.join(journal, table + ".partial.csv"), text)
            shutil.copy(os.path.join(whole, "provenance.json"), os.path.join(journal, "provenance.json"))
            add(cat, "%s resumed from a journal: %s" % (command, label),
                [command, scen, "--out", out, "--threads", "1"] + extra, "accept", [],
                outputs=[out], post=same_file(table + ".csv", os.path.join(whole, table + ".csv")))


def wait_for(path, process, seconds=60):
    """Until `path` exists or the process ended; whether it exists."""
    t0 = time.time()
    while not os.path.exists(path) and process.poll() is None and time.time() - t0 < seconds:  # noqa
        time.sleep(0.005)
    return os.path.exists(path)


def gen_race(quick):
    """Commands racing for one output folder: a second writer is refused, a
    file put into the folder during a run survives and the result is kept
    beside it; never two exits 0 for one folder, never a lost file."""
    cat = "race"
    long_sweep = scenario_file(cat, sweep_text('analysis = "simulation"\nduration = 6.0\n',
                                               axis("controller.k", "1e4", "1e6", 160, '"log"')), "rsw")
    for command, extra in [("sweep", []), ("robust", ["--samples", "400"])]:
        scen = long_sweep if command == "sweep" else scenario_file(
            cat, robust_text(head=ROBUST_HEAD.replace('"linear"', '"simulation"'),
                             base=fig05b(duration="4.0")), "rrb")
        out = fresh("out/race")
        journal = os.path.join(os.path.dirname(out), "." + os.path.basename(out) + ".journal")
        seen = {}

        def second_writer(p, out=out, journal=journal, seen=seen, scen=scen, command=command, extra=extra):
            seen["locked"] = wait_for(journal, p)
            seen["second"] = run_program([command, scen, "--out", out, "--threads", "1"] + extra, SCRATCH)

        def both_checked(case, res, seen=seen):
            second = seen.get("second")
            if not seen.get("locked") or second is None or second.seconds > res.seconds:
                return "the first run ended before the race (lengthen it)"
            if second.rc == 0 and res.rc == 0:
                return "two runs into one folder both exited 0"
            if second.rc != 0 and "another command" not in second.stderr:
                return "second writer refused unclearly: %s" % first_line(second.stderr)
            return None

        add(cat, "%s: a second run into the folder being written" % command,
            [command, scen, "--out", out, "--threads", "1"] + extra, "accept", [], outputs=[out],
            during=second_writer, post=both_checked, post_always=True)

        out = fresh("out/race")
        journal = os.path.join(os.path.dirname(out), "." + os.path.basename(out) + ".journal")
        notes = os.path.join(out, "notes.txt")
        mark = {}

        def user_file(p, out=out, journal=journal, notes=notes, mark=mark):
            mark["started"] = wait_for(journal, p)
            write(notes, "mine\n")
            mark["in time"] = p.poll() is None

        def notes_kept(case, res, notes=notes, mark=mark):
            if not mark.get("in time"):
                return "the run ended before the file was put in (lengthen it)"
            if not os.path.exists(notes):
                return "a file put into the folder during the run was deleted"
            return None

        add(cat, "%s: a user's file put into the folder during the run" % command,
            [command, scen, "--out", out, "--threads", "1"] + extra, "refuse", ["changed while"],
            during=user_file, post=notes_kept, post_always=True)


# ---------------------------------------------------------------------------
# Main
# ---------------------------------------------------------------------------

GENERATORS = {"robot": gen_robot, "scenario": gen_scenario, "sweep": gen_sweep,
              "robust": gen_robust, "identify": gen_identify, "modes": gen_modes, "flags": gen_flags,
              "output": gen_output, "journal": gen_journal, "race": gen_race}


def main():
    global BIN, SCRATCH, TIMEOUT
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("fistage")
    ap.add_argument("--quick", action="store_true", help="fewer values, fewer files")
    ap.add_argument("--only", choices=CATEGORIES, action="append")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--timeout", type=float, default=30.0)
    a = ap.parse_args()
    BIN = os.path.abspath(a.fistage)
    TIMEOUT = a.timeout
    if not os.access(BIN, os.X_OK):
        sys.exit("not an executable: %s" % BIN)
    SCRATCH = tempfile.mkdtemp(prefix="fistage-adversarial-")
    cats = a.only or CATEGORIES
    t0 = time.time()
    print("scratch folder: %s" % SCRATCH, file=sys.stderr)
    for c in cats:
        if c in GENERATORS:
            n0 = len(CASES)
            GENERATORS[c](a.quick)
            print("generated %d %s cases" % (len(CASES) - n0, c), file=sys.stderr)
        else:
            print("warning: category %s not implemented" % c, file=sys.stderr)

    results = [None] * len(CASES)

    def work(i):
        c = CASES[i]
        before = {p: snapshot(p) for p in c.guard}
        res = run_program(c.args, c.cwd, during=c.during)
        return classify(c, res, before) + (res,)

    done = [0]
    # Cases with a guard or post check run one at a time, after the others:
    # they share folders with their setups.
    free = [i for i, c in enumerate(CASES) if not c.guard and not c.post]
    serial = [i for i, c in enumerate(CASES) if c.guard or c.post]
    with ThreadPoolExecutor(max_workers=max(1, a.jobs)) as ex:
        for i, r in zip(free, ex.map(work, free)):
            results[i] = r
            done[0] += 1
            if done[0] % 200 == 0:
                print("  %d/%d cases, %.0f s" % (done[0], len(CASES), time.time() - t0), file=sys.stderr)
    for i in serial:
        results[i] = work(i)
    elapsed = time.time() - t0
    report(cats, results, elapsed)
    bad = sum(1 for r in results if r[0] in BAD)
    sys.exit(1 if bad else 0)


def report(cats, results, elapsed):
    rows = {c: dict.fromkeys(OUTCOMES, 0) for c in cats}
    for c, r in zip(CASES, results):
        rows[c.cat][r[0]] += 1
    print("| category | cases | " + " | ".join(OUTCOMES) + " |")
    print("|---|---:|" + "---:|" * len(OUTCOMES))
    tot = dict.fromkeys(OUTCOMES, 0)
    for c in cats:
        n = sum(rows[c].values())
        print("| %s | %d | %s |" % (c, n, " | ".join(str(rows[c][o]) for o in OUTCOMES)))
        for o in OUTCOMES:
            tot[o] += rows[c][o]
    print("| **total** | %d | %s |" % (sum(tot.values()), " | ".join(str(tot[o]) for o in OUTCOMES)))
    print()
    print("%d cases in %.1f s; scratch folder (reproducers use it): %s" % (len(CASES), elapsed, SCRATCH))
    for o in ("crash", "hang", "wrong answer", "unclear error"):
        items = [(c, r) for c, r in zip(CASES, results) if r[0] == o]
        if not items:
            continue
        print()
        print("## %s (%d)" % (o, len(items)))
        print()
        for c, r in items:
            print("- [%s] %s: %s" % (c.cat, c.name, r[1]))
            print("  `%s`" % c.repro())
    refused = [(c, r) for c, r in zip(CASES, results) if c.expect == "accept" and r[0] in
               ("clear error", "unclear error")]
    if refused:
        print()
        print("## legitimate input refused (counted above as an error; listed for review) (%d)" % len(refused))
        print()
        for c, r in refused:
            print("- [%s] %s: %s" % (c.cat, c.name, r[1]))
            print("  `%s`" % c.repro())


if __name__ == "__main__":
    main()
