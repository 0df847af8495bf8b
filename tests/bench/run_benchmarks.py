#!/usr/bin/env python3
"""run_benchmarks.py -- the vdb_shell benchmark suite in one command.

Not part of the ctest run. Runs the built binaries as child processes, prints Markdown tables on
stdout and writes OUT/results.md and OUT/results.json (every raw number, every run):

    /usr/bin/python3 tests/bench/run_benchmarks.py --build build --out /tmp/bench-results
    /usr/bin/python3 tests/bench/run_benchmarks.py --build build --out /tmp/bench-q --quick

Sections (--sections, comma-separated; default all):
  table1   the paper's generated shapes (vdb_shell_shapes) at 128^3 through the CLI: median wall
           time of --repeats runs (default 5), the report's numbers, the independent checker once
           per shape, beside the paper's Table 1 row.
  meshes   the same for the watertight meshes of --meshes (the shared README says which are
           broken; those are skipped and listed).
  fine     meshes much finer than the grid at --table1-resolution (FINE_MESHES: a 50,880-face
           sphere, a 40,368-face box, spot, fertility and fandisk subdivided to 94k-207k faces):
           per-stage time, trace samples and wall microseconds per sample, stop reasons,
           coverage (one run each unless --fine-repeats).
  scaling  fandisk and fertility x16 (fertility.off subdivided twice, 144,000 faces, written into
           OUT/work by vdb_shell_bench_fields --write-subdivided) at --resolutions: time per stage
           (the report's timings_s), peak RSS of the process (wait4 ru_maxrss), and the ratio to
           OpenVDB's narrow-band meshToLevelSet floor (vdb_shell_bench_fields --floor), measured
           alternately in the same run.
  threads  the same two meshes at --thread-resolution with -j 1 and -j 2 (alternating): per-stage
           medians and speed-ups.
  peers    TetGen (tetgen -pQ and -pqQ) on the table1 and meshes surfaces: wall time, tets, min and
           median volume-length quality (vdb_shell's formula, core/assemble/quality.cpp),
           beside vdb_shell.
  layers   --layers K / --layer-ratio r (LAYER_CASES: 1, 2, 5 layers, 5 at ratio 1.5) on fandisk,
           spot, fertility and a 3,040-face sphere at --table1-resolution: tets, coverage,
           quality (min, 5th percentile, median, smallest dihedral angle), validity and total
           seconds (medians of --repeats runs), the independent checker once per case.
  targets  (always) the performance targets, met or missed by how much; nothing is asserted.

--quick: 1 run per point, scaling at 64 and 128 on fandisk only, threads at 128 (about 1-2
minutes on 2 cores): for trying the driver out, not for numbers.
A failing run (non-zero exit or timeout, --timeout seconds per run) is recorded as failed with the
last line of its stderr; the driver carries on. Ctrl-C / SIGTERM stop the running child and write
what was measured. Exit status: 0 (also when runs failed), 2 if the driver cannot run (no
vdb_shell in --build), 130 when interrupted.

Only the Python standard library and numpy.
"""

import argparse
import datetime
import json
import math
import os
import platform
import re
import shutil
import signal
import statistics
import subprocess
import sys
import time
import xml.etree.ElementTree as ET

try:
    import numpy as np
except ImportError:  # pragma: no cover
    sys.stderr.write("run_benchmarks.py: needs numpy (apt-get install python3-numpy; run it "
                     "with /usr/bin/python3)\n")
    sys.exit(2)

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.normpath(os.path.join(HERE, "..", ".."))
SHARED = os.path.normpath(os.path.join(REPO, "..", "shared"))

ALL_SECTIONS = ["table1", "meshes", "fine", "scaling", "threads", "peers", "layers"]
# --layers section: (layers, ratio) per mesh; meshes from --meshes, and one generated sphere.
LAYER_CASES = [(1, 1.0), (2, 1.0), (5, 1.0), (5, 1.5)]
LAYER_MESHES = [("fandisk", "fandisk.obj"), ("spot", "spot.obj"), ("fertility", "fertility.off")]

# The fine meshes of the fine section: (label, how it is made, argument, detail or levels).
# Subdivided meshes are the shared ones midpoint-subdivided (vdb_shell_bench_fields
# --write-subdivided; 4^levels times the faces), shapes come from vdb_shell_shapes.
FINE_MESHES = [("sphere-d8", "shape", "sphere", 8),         # 50,880 faces
               ("box-d29", "shape", "box", 29),             # 40,368 faces
               ("spot_x16", "subdivided", "spot.obj", 2),  # 93,696 faces
               ("fertility_x16", "subdivided", "fertility.off", 2),  # 144,000 faces
               ("fandisk_x16", "subdivided", "fandisk.obj", 2)]      # 207,136 faces
TARGET_FINE_SPHERE_S = 5.0
# Whole runs of fine meshes at 128^3: (label, limit s, what the limit stands for). The targets
# name scans of 86k and 269k faces; spot x16 (94k) and fandisk x16 (207k) stand in for them.
TARGET_FINE_RUNS = [("spot_x16", 3.0, "an 86k-face scan"),
                    ("fandisk_x16", 10.0, "a 269k-face scan; 207k faces here")]

# The paper's Table 1 ("Volumetric Shells using Path Tracing", 128^3): name, F, time s, T,
# point size, step size. Teapot and dragon have no generated shape here.
PAPER_TABLE1 = [
    ("box", 48, 0.04, 144, 0.0150, 0.0043),
    ("box", 192, 0.06, 576, 0.0150, 0.0043),
    ("cylinder", 48, 0.04, 144, 0.0141, 0.0035),
    ("cylinder", 192, 0.09, 576, 0.0141, 0.035),
    ("pointy", 96, 0.15, 288, 0.0110, 0.0024),
    ("star", 588, 0.57, 1764, 0.0123, 0.0006),
    ("horn", 408, 0.11, 1224, 0.0116, 0.0020),
    ("tube", 512, 0.17, 1536, 0.0135, 0.0028),
    ("sphere", 760, 561.66, 2280, 0.0150, 0.0043),
    ("teapot", 1056, 567.09, 3168, 0.0115, 0.0024),
    ("propeller", 1200, 569.79, 3600, 0.0124, 0.0009),
    ("funnel", 1280, 559.61, 3840, 0.0127, 0.0016),
    ("dragon", 1496, 558.47, 4488, 0.0128, 0.003),
    ("bowl", 2680, 562.22, 8040, 0.0124, 0.0010),
]

# (shape, detail) run in table1, in the paper's order; shapes of `vdb_shell_shapes --list` not
# named here are appended at detail 1 (e.g. torus, which the paper does not have).
TABLE1_JOBS = [("box", 1), ("box", 2), ("cylinder", 1), ("cylinder", 2), ("pointy", 1),
               ("star", 1), ("horn", 1), ("tube", 1), ("sphere", 1), ("propeller", 1),
               ("funnel", 1), ("bowl", 1)]

# The performance targets (reported by the targets section, never asserted).
TARGET_TABLE1_S = 0.2
TARGET_FLOOR_RATIO_512 = 2.0
TARGET_1024_S = 20.0
TARGET_1024_PEAK_KIB = 3 * 1024 * 1024  # 3 GiB
TARGET_SPEEDUP = 1.8  # 1 -> 2 threads, of the trace and of assemble (validity search + check)


# ----------------------------------------------------------------------------------------------
# Small helpers


def log(msg):
    sys.stderr.write("[bench %s] %s\n" % (time.strftime("%H:%M:%S"), msg))
    sys.stderr.flush()


def median(values):
    values = [v for v in values if v is not None]
    return statistics.median(values) if values else None


def fmt(x, digits=3):
    """A number for a table cell; '' for None."""
    if x is None:
        return ""
    if isinstance(x, bool):
        return "yes" if x else "no"
    if isinstance(x, int):
        return "{:,}".format(x)
    if isinstance(x, float):
        if math.isnan(x):
            return "nan"
        if x != 0 and abs(x) < 10 ** (-digits):
            return "%.1e" % x
        return "%.*f" % (digits, x)
    return str(x)


def cell(x):
    return str(x).replace("|", "\\|").replace("\n", " ")


def md_table(header, rows):
    out = ["| " + " | ".join(cell(h) for h in header) + " |",
           "|" + "---|" * len(header)]
    for r in rows:
        out.append("| " + " | ".join(cell(c) for c in r) + " |")
    return "\n".join(out)


def kib_to_mib(k):
    return None if k is None else k / 1024.0


def get(d, *keys):
    """d[k1][k2]...; None where any is missing."""
    for k in keys:
        if not isinstance(d, dict) or k not in d:
            return None
        d = d[k]
    return d


# ----------------------------------------------------------------------------------------------
# Running child processes


# The children are started by a small launcher process, not by this driver: Linux carries the peak
# RSS of the process that forks (its high-water mark, not its current size) into the child's
# ru_maxrss, so children forked from this driver would report at least the driver's own peak
# (numpy, a parsed 400k-tet .vtu: hundreds of MiB). The launcher stays at ~10 MiB, which is then
# the floor of every "peak" column. It runs one job at a time: reads a JSON line (cmd, cwd,
# timeout, stdout/stderr paths), answers {"pid": ...} once started, then the result line.
# SIGUSR1 makes it stop the running child (SIGTERM, SIGKILL 10 s later); so does the timeout.
LAUNCHER = r"""
import json, os, signal, subprocess, sys, threading, time
lock = threading.RLock()
state = {"pid": None, "done": True, "reason": None}
def stop(reason):
    with lock:
        if state["done"] or state["pid"] is None:
            return
        state["reason"] = state["reason"] or reason
        try:
            os.kill(state["pid"], signal.SIGTERM)
        except OSError:
            pass
    def hard():
        with lock:
            if not state["done"]:
                try:
                    os.kill(state["pid"], signal.SIGKILL)
                except OSError:
                    pass
    t = threading.Timer(10.0, hard)
    t.daemon = True
    t.start()
signal.signal(signal.SIGINT, lambda *_: None)  # Ctrl-C reaches the child itself
signal.signal(signal.SIGUSR1, lambda *_: stop("interrupt"))
for line in sys.stdin:
    job = json.loads(line)
    res = {"rc": None, "wall_s": None, "maxrss_kib": None, "user_s": None, "sys_s": None,
           "timed_out": False, "error": None}
    try:
        with open(job["stdout"], "wb") as so, open(job["stderr"], "wb") as se:
            t0 = time.perf_counter()
            p = subprocess.Popen(job["cmd"], cwd=job["cwd"], stdin=subprocess.DEVNULL,
                                 stdout=so, stderr=se)
    except OSError as e:
        res["error"] = "cannot start: %s" % e
        sys.stdout.write(json.dumps(res) + "\n")
        sys.stdout.flush()
        continue
    with lock:
        state.update(pid=p.pid, done=False, reason=None)
    sys.stdout.write(json.dumps({"pid": p.pid}) + "\n")
    sys.stdout.flush()
    timer = threading.Timer(job["timeout"], stop, args=("timeout",))
    timer.daemon = True
    timer.start()
    os.waitid(os.P_PID, p.pid, os.WEXITED | os.WNOWAIT)  # exited, not yet reaped
    wall = time.perf_counter() - t0
    timer.cancel()
    with lock:
        state["done"] = True
        _, status, ru = os.wait4(p.pid, 0)
    p.returncode = os.waitstatus_to_exitcode(status)
    res.update(rc=p.returncode, wall_s=wall, maxrss_kib=ru.ru_maxrss, user_s=ru.ru_utime,
               sys_s=ru.ru_stime, timed_out=state["reason"] == "timeout")
    sys.stdout.write(json.dumps(res) + "\n")
    sys.stdout.flush()
"""


class Runner:
    """Runs one command at a time through the launcher: wall time, exit code, peak RSS
    (wait4 ru_maxrss, KiB), user/system CPU seconds, stderr tail."""

    def __init__(self, timeout, tmpdir):
        self.timeout = timeout
        self.tmpdir = tmpdir
        os.makedirs(tmpdir, exist_ok=True)
        self.launcher = subprocess.Popen([sys.executable, "-S", "-E", "-c", LAUNCHER],
                                         stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                         text=True, bufsize=1)

    def close(self):
        if self.launcher and self.launcher.poll() is None:
            self.launcher.stdin.close()
            try:
                self.launcher.wait(timeout=30)
            except subprocess.TimeoutExpired:
                self.launcher.kill()
                self.launcher.wait()
        self.launcher = None

    def _reply(self):
        line = self.launcher.stdout.readline()
        if not line:
            raise RuntimeError("the launcher process ended unexpectedly")
        return json.loads(line)

    def run(self, cmd, cwd=None, timeout=None, keep_stdout=False):
        timeout = self.timeout if timeout is None else timeout
        cmd = [str(c) for c in cmd]
        out_path = os.path.join(self.tmpdir, "stdout")
        err_path = os.path.join(self.tmpdir, "stderr")
        job = {"cmd": cmd, "cwd": cwd, "timeout": timeout, "stdout": out_path,
               "stderr": err_path}
        self.launcher.stdin.write(json.dumps(job) + "\n")
        self.launcher.stdin.flush()
        try:
            res = self._reply()
            if "pid" in res:
                res = self._reply()
        except KeyboardInterrupt:
            # stop the child (Ctrl-C has reached it already; SIGTERM does not), collect it
            self.launcher.send_signal(signal.SIGUSR1)
            res = self._reply()
            if "pid" in res:
                self.launcher.send_signal(signal.SIGUSR1)
                self._reply()
            raise
        rec = {"cmd": cmd, "rc": res["rc"], "ok": False, "wall_s": res["wall_s"],
               "maxrss_kib": res["maxrss_kib"], "user_s": res["user_s"], "sys_s": res["sys_s"],
               "timed_out": bool(res["timed_out"]), "error": res["error"]}
        if res["error"]:
            return rec
        out = err = ""
        try:
            with open(out_path, "rb") as f:
                out = f.read().decode("utf-8", "replace") if keep_stdout else ""
            with open(err_path, "rb") as f:
                f.seek(max(0, os.path.getsize(err_path) - 65536))
                err = f.read().decode("utf-8", "replace")
        except OSError:
            pass
        rec["ok"] = rec["rc"] == 0 and not rec["timed_out"]
        if keep_stdout:
            rec["stdout"] = out
        lines = [ln for ln in err.splitlines() if ln.strip()]
        rec["stderr_tail"] = lines[-3:]
        if not rec["ok"]:
            if rec["timed_out"]:
                rec["error"] = "timed out after %g s" % timeout
            else:
                rec["error"] = "exit %d: %s" % (rec["rc"], lines[-1] if lines else "(no stderr)")
        return rec


def failure_text(rec, limit=160):
    """'failed (reason)' for a table cell; the full message stays in results.json."""
    if not rec:
        return "not run"
    err = rec.get("error") or "?"
    return "failed (%s)" % (err if len(err) <= limit else err[:limit - 3] + "...")


# ----------------------------------------------------------------------------------------------
# Meshes, shells, quality


def read_surface(path):
    """(points Nx3 float64, triangles Mx3 int) of an .obj or .off surface; polygons as fans."""
    pts, tris = [], []
    ext = os.path.splitext(path)[1].lower()
    with open(path, "r", errors="replace") as f:
        if ext == ".obj":
            for line in f:
                tok = line.split()
                if not tok:
                    continue
                if tok[0] == "v":
                    pts.append([float(t) for t in tok[1:4]])
                elif tok[0] == "f":
                    idx = []
                    for t in tok[1:]:
                        i = int(t.split("/")[0])
                        idx.append(i - 1 if i > 0 else len(pts) + i)
                    for k in range(1, len(idx) - 1):
                        tris.append([idx[0], idx[k], idx[k + 1]])
        elif ext == ".off":
            words = []
            for line in f:
                line = line.split("#", 1)[0]
                words.extend(line.split())
            if not words or not words[0].endswith("OFF"):
                raise ValueError("%s: not an OFF file" % path)
            pos = 1 if words[0] == "OFF" else 0
            if words[0] != "OFF":  # 'OFF' glued to nothing else is all we handle
                raise ValueError("%s: unsupported OFF variant %s" % (path, words[0]))
            nv, nf = int(words[pos]), int(words[pos + 1])
            pos += 3
            for _ in range(nv):
                pts.append([float(w) for w in words[pos:pos + 3]])
                pos += 3
            for _ in range(nf):
                n = int(words[pos])
                idx = [int(w) for w in words[pos + 1:pos + 1 + n]]
                pos += 1 + n
                for k in range(1, n - 1):
                    tris.append([idx[0], idx[k], idx[k + 1]])
        else:
            raise ValueError("%s: only .obj and .off are read here" % path)
    return np.asarray(pts, dtype=np.float64), np.asarray(tris, dtype=np.int64)


def write_off(path, points, tris):
    with open(path, "w") as f:
        f.write("OFF\n%d %d 0\n" % (len(points), len(tris)))
        for p in points:
            f.write("%r %r %r\n" % (float(p[0]), float(p[1]), float(p[2])))
        for t in tris:
            f.write("3 %d %d %d\n" % (t[0], t[1], t[2]))


def read_vtu(path):
    """(points, tets) of an ASCII .vtu written by vdb_shell."""
    root = ET.parse(path).getroot()
    arrays = {}
    for da in root.iter("DataArray"):
        arrays[da.get("Name")] = da.text or ""
    pts = np.array(arrays["Points"].split(), dtype=np.float64).reshape(-1, 3)
    conn = np.array(arrays["connectivity"].split(), dtype=np.int64)
    offs = np.array(arrays["offsets"].split(), dtype=np.int64)
    if len(offs) and not np.all(np.diff(np.concatenate([[0], offs])) == 4):
        raise ValueError("%s: not all cells are tetrahedra" % path)
    return pts, conn.reshape(-1, 4)


def read_tetgen(prefix):
    """(points, tets) of TetGen's PREFIX.node / PREFIX.ele (any index base)."""
    def numbers(path):
        rows = []
        with open(path) as f:
            for line in f:
                line = line.split("#", 1)[0].split()
                if line:
                    rows.append(line)
        return rows

    node = numbers(prefix + ".node")
    n, dim = int(node[0][0]), int(node[0][1])
    body = node[1:1 + n]
    ids = np.array([int(r[0]) for r in body], dtype=np.int64)
    pts = np.array([[float(x) for x in r[1:1 + dim]] for r in body], dtype=np.float64)
    ele = numbers(prefix + ".ele")
    m, per = int(ele[0][0]), int(ele[0][1])
    tets = np.array([[int(x) for x in r[1:5]] for r in ele[1:1 + m]], dtype=np.int64)
    if per != 4 and per != 10:
        raise ValueError("%s.ele: %d nodes per tet" % (prefix, per))
    base = int(ids.min()) if len(ids) else 0
    lookup = np.full(int(ids.max()) - base + 1 if len(ids) else 0, -1, dtype=np.int64)
    lookup[ids - base] = np.arange(len(ids))
    return pts, lookup[tets - base]


def tet_quality(points, tets):
    """Volume-length ratio Q = 6 sqrt(2) V / l_rms^3 per tet, V the signed volume
    dot(cross(b - a, c - a), d - a) / 6: the formula of core/assemble/quality.cpp tet_quality()
    (regular tet 1, flat 0, inverted < 0; 0 when every edge has zero length)."""
    if len(tets) == 0:
        return np.zeros(0)
    a, b, c, d = (points[tets[:, k]] for k in range(4))

    def n2(u):
        return np.einsum("ij,ij->i", u, u)

    sum2 = n2(b - a) + n2(c - a) + n2(d - a) + n2(c - b) + n2(d - b) + n2(d - c)
    vol = np.einsum("ij,ij->i", np.cross(b - a, c - a), d - a) / 6.0
    q = np.zeros(len(tets))
    ok = sum2 > 0.0
    l_rms = np.sqrt(sum2[ok] / 6.0)
    q[ok] = 6.0 * math.sqrt(2.0) * vol[ok] / (l_rms * l_rms * l_rms)
    return q


def ratio_text(ratio):
    """'2.57x', or '' when there is no ratio."""
    return "%sx" % fmt(ratio, 2) if ratio else ""


def quality_summary(q):
    """min and median like core/assemble/quality.cpp summarize_quality (median of an even count is
    the mean of the two middle values, as numpy's)."""
    if len(q) == 0:
        return {"tets": 0, "min": None, "median": None, "mean": None, "non_positive": 0}
    return {"tets": int(len(q)), "min": float(np.min(q)), "median": float(np.median(q)),
            "mean": float(np.mean(q)), "non_positive": int(np.sum(~(q > 0)))}


def same_value(a, b):
    return a is not None and b is not None and abs(a - b) <= 1e-9 + 1e-9 * abs(b)


# ----------------------------------------------------------------------------------------------
# The suite


class Suite:
    def __init__(self, args):
        self.args = args
        self.out = os.path.abspath(args.out)
        self.work = os.path.join(self.out, "work")
        os.makedirs(self.work, exist_ok=True)
        self.runner = Runner(args.timeout, os.path.join(self.work, "logs"))
        self.results = {"started": datetime.datetime.now().isoformat(timespec="seconds"),
                        "options": {k: v for k, v in vars(args).items()},
                        "machine": {}, "sections": {}}
        self.markdown = []
        self.bin = {}
        self.python = args.python
        self.rendered = set()
        self.surface_faces = {}

    # -- setup ---------------------------------------------------------------------------------

    def find_binaries(self):
        build = os.path.abspath(self.args.build)
        wanted = {"vdb_shell": ["cli/vdb_shell", "vdb_shell"],
                  "shapes": ["assets/vdb_shell_shapes", "vdb_shell_shapes"],
                  "fields_bench": ["tests/bench/vdb_shell_bench_fields"]}
        for key, rels in wanted.items():
            for rel in rels:
                p = os.path.join(build, rel)
                if os.path.isfile(p) and os.access(p, os.X_OK):
                    self.bin[key] = p
                    break
        tg = self.args.tetgen or shutil.which("tetgen")
        if tg:
            self.bin["tetgen"] = tg
        if os.path.isfile(self.args.checker):
            self.bin["checker"] = self.args.checker
        self.results["binaries"] = dict(self.bin)
        if "vdb_shell" not in self.bin:
            sys.stderr.write("run_benchmarks.py: no vdb_shell under %s (cli/vdb_shell); build "
                             "first: cmake --build %s\n" % (build, self.args.build))
            sys.exit(2)

    def machine(self, when):
        m = self.results["machine"]
        load = os.getloadavg()
        m["load_average_" + when] = [round(x, 2) for x in load]
        if when != "start":
            return
        m["nproc"] = os.cpu_count()
        try:
            m["nproc_available"] = len(os.sched_getaffinity(0))
        except AttributeError:
            pass
        model = None
        try:
            with open("/proc/cpuinfo") as f:
                for line in f:
                    if line.lower().startswith("model name"):
                        model = line.split(":", 1)[1].strip()
                        break
        except OSError:
            pass
        m["cpu_model"] = model or platform.processor() or platform.machine()
        try:
            with open("/proc/meminfo") as f:
                for line in f:
                    if line.startswith("MemTotal:"):
                        m["ram_gib"] = round(int(line.split()[1]) / 1024.0 / 1024.0, 1)
        except OSError:
            pass
        m["kernel"] = platform.release()
        m["python"] = platform.python_version()
        m["numpy"] = np.__version__

        def git(*a):
            try:
                return subprocess.run(["git", "-C", REPO] + list(a), capture_output=True,
                                      text=True, timeout=30).stdout.strip()
            except (OSError, subprocess.SubprocessError):
                return None

        m["git_commit"] = git("rev-parse", "HEAD")
        status = git("status", "--porcelain", "--untracked-files=no")
        m["git_dirty"] = bool(status) if status is not None else None
        v = self.runner.run([self.bin["vdb_shell"], "--version"], keep_stdout=True, timeout=60)
        m["vdb_shell_version"] = (v.get("stdout") or "").strip() or None
        if "tetgen" in self.bin:
            m["tetgen"] = self.bin["tetgen"]

    def machine_markdown(self):
        m = self.results["machine"]
        commit = m.get("git_commit") or "?"
        if m.get("git_dirty"):
            commit += " (+ uncommitted changes)"
        rows = [[m.get("nproc"), m.get("cpu_model"), "%s GiB" % m.get("ram_gib"),
                 " ".join(str(x) for x in m.get("load_average_start", [])),
                 " ".join(str(x) for x in m.get("load_average_end", [])), commit,
                 m.get("vdb_shell_version") or ""]]
        return md_table(["nproc", "CPU", "RAM", "load start (1/5/15 min)",
                         "load end", "git commit", "vdb_shell"], rows)

    def emit(self, text):
        """Markdown to stdout now and to results.md at the end."""
        self.markdown.append(text)
        sys.stdout.write(text + "\n\n")
        sys.stdout.flush()

    def save(self):
        self.results["finished"] = datetime.datetime.now().isoformat(timespec="seconds")
        tmp = os.path.join(self.out, "results.json.tmp")
        with open(tmp, "w") as f:
            json.dump(self.results, f, indent=1, default=str)
        os.replace(tmp, os.path.join(self.out, "results.json"))
        tmp = os.path.join(self.out, "results.md.tmp")
        with open(tmp, "w") as f:
            f.write("\n\n".join(self.markdown) + "\n")
        os.replace(tmp, os.path.join(self.out, "results.md"))

    # -- one vdb_shell shell, repeated ---------------------------------------------------------

    def shell_case(self, label, surface, res, repeats, folder, threads=None, checker=True,
                   verify_quality=True, keep_shell=True, extra=()):
        """Runs vdb_shell SURFACE -o X.vtu --resolution RES --report X.json [EXTRA...]
        `repeats` times."""
        d = os.path.join(self.work, folder)
        os.makedirs(d, exist_ok=True)
        shell = os.path.join(d, "%s_r%d.vtu" % (label, res))
        case = {"label": label, "surface": surface, "resolution": res, "threads": threads,
                "runs": []}
        for k in range(repeats):
            report_path = os.path.join(d, "%s_r%d.run%d.json" % (label, res, k))
            cmd = [self.bin["vdb_shell"], surface, "-o", shell, "--resolution", res,
                   "--report", report_path]
            if threads:
                cmd += ["-j", threads]
            cmd += list(extra)
            rec = self.runner.run(cmd)
            if rec["ok"]:
                try:
                    with open(report_path) as f:
                        rec["report"] = json.load(f)
                except (OSError, ValueError) as e:
                    rec["ok"] = False
                    rec["error"] = "no readable report: %s" % e
            case["runs"].append(rec)
            if not rec["ok"]:
                log("  %s @%d: %s" % (label, res, rec["error"]))
                break  # a failure repeats; do not spend the time again
        self.summarize_case(case)
        if case["ok"] and verify_quality:
            case["quality_check"] = self.verify_quality(shell, case["report"])
        if case["ok"] and checker and "checker" in self.bin and not self.args.no_checker:
            case["checker"] = self.run_checker(surface, shell, d, label, res)
        if not keep_shell and os.path.exists(shell):
            os.remove(shell)
        return case

    @staticmethod
    def summarize_case(case):
        ok_runs = [r for r in case["runs"] if r["ok"]]
        case["ok"] = bool(case["runs"]) and len(ok_runs) == len(case["runs"])
        case["error"] = None if case["ok"] else next(
            (r["error"] for r in case["runs"] if not r["ok"]), "not run")
        if not ok_runs:
            case["report"] = None
            return
        case["report"] = ok_runs[-1]["report"]
        case["wall_s"] = median([r["wall_s"] for r in ok_runs])
        case["wall_s_all"] = [r["wall_s"] for r in ok_runs]
        case["maxrss_kib"] = median([r["maxrss_kib"] for r in ok_runs])
        stages = []
        for r in ok_runs:
            for key in (r["report"].get("timings_s") or {}):
                if key not in stages:
                    stages.append(key)
        case["stages"] = stages
        case["timings_median_s"] = {
            key: median([get(r["report"], "timings_s", key) for r in ok_runs]) for key in stages}

    def verify_quality(self, shell, report):
        try:
            pts, tets = read_vtu(shell)
        except (OSError, ValueError, KeyError, ET.ParseError) as e:
            return {"error": str(e)}
        s = quality_summary(tet_quality(pts, tets))
        rmin, rmed = get(report, "quality", "min"), get(report, "quality", "median")
        return {"python_min": s["min"], "python_median": s["median"], "report_min": rmin,
                "report_median": rmed, "tets": s["tets"],
                "match": same_value(s["min"], rmin) and same_value(s["median"], rmed)}

    def run_checker(self, surface, shell, d, label, res):
        out = os.path.join(d, "%s_r%d.check.json" % (label, res))
        cmd = [self.python, self.bin["checker"], surface, shell, "--samples",
               self.args.samples, "--json", out]
        rec = self.runner.run(cmd)
        res_ = {"rc": rec["rc"], "wall_s": rec["wall_s"], "error": None}
        # exit 0 valid, 1 invalid (both write the JSON), 2 unreadable input
        if rec["rc"] in (0, 1) and not rec["timed_out"]:
            try:
                with open(out) as f:
                    rep = json.load(f)
                res_["valid"] = bool(get(rep, "verdict", "valid"))
                res_["valid_strict"] = get(rep, "verdict", "valid_strict")
                res_["failed"] = get(rep, "verdict", "failed")
                res_["coverage"] = get(rep, "volume", "coverage")
                res_["coverage_mc"] = get(rep, "monte_carlo", "coverage_mc", "value")
                res_["residual_mc"] = get(rep, "monte_carlo", "residual_fraction", "value")
            except (OSError, ValueError) as e:
                res_["error"] = "unreadable checker JSON: %s" % e
        else:
            res_["error"] = rec["error"]
        return res_

    def affordable(self, rec):
        """Whether another repeat of a run like `rec` is worth its time."""
        return rec.get("wall_s") is not None and rec["wall_s"] <= self.args.affordable_s

    @staticmethod
    def largest_stage(case):
        t = {k: v for k, v in (case.get("timings_median_s") or {}).items()
             if k != "total" and v is not None}
        if not t:
            return ""
        k = max(t, key=t.get)
        return "%s %s" % (k, fmt(t[k], 2))

    @staticmethod
    def checker_cells(case):
        c = case.get("checker")
        if not c:
            return ["", ""]
        if c.get("error"):
            return ["error: " + c["error"], ""]
        verdict = "VALID" if c.get("valid") else "INVALID " + ",".join(c.get("failed") or [])
        return [verdict, fmt(c.get("coverage"), 3)]

    # -- table1 --------------------------------------------------------------------------------

    def shape_list(self):
        rec = self.runner.run([self.bin["shapes"], "--list"], keep_stdout=True, timeout=60)
        shapes = []
        for line in (rec.get("stdout") or "").splitlines()[1:]:
            m = re.match(r"^(\S+)\s+(\d+)\s", line)
            if m:
                shapes.append((m.group(1), int(m.group(2))))
        return shapes

    def make_shape(self, name, detail):
        d = os.path.join(self.work, "shapes")
        os.makedirs(d, exist_ok=True)
        label = name if detail == 1 else "%s-d%d" % (name, detail)
        path = os.path.join(d, label + ".obj")
        if not os.path.exists(path):
            rec = self.runner.run([self.bin["shapes"], name, "-o", path, "--detail", detail])
            if not rec["ok"]:
                return label, None, rec["error"]
        return label, path, None

    @staticmethod
    def table1_jobs(names):
        """(shape, detail) to run: the paper's order, then the other shapes at detail 1."""
        jobs = [j for j in TABLE1_JOBS if j[0] in names]
        return jobs + [(n, 1) for n in names if n not in {j[0] for j in TABLE1_JOBS}]

    @staticmethod
    def paper_row(name, faces):
        rows = [r for r in PAPER_TABLE1 if r[0] == name]
        if not rows or faces is None:
            return None
        return min(rows, key=lambda r: abs(r[1] - faces))

    def section_table1(self):
        if "shapes" not in self.bin:
            self.emit("## Table 1\n\nskipped: no vdb_shell_shapes in the build folder.")
            return
        names = [n for n, _ in self.shape_list()]
        jobs = self.table1_jobs(names)
        res = self.args.table1_resolution
        cases = []
        for name, detail in jobs:
            label, path, err = self.make_shape(name, detail)
            log("table1: %s @%d x%d" % (label, res, self.args.repeats))
            if path is None:
                cases.append({"label": label, "shape": name, "detail": detail, "ok": False,
                              "error": err, "runs": []})
                continue
            case = self.shell_case(label, path, res, self.args.repeats, "table1")
            case.update(shape=name, detail=detail)
            cases.append(case)
            self.results["sections"]["table1"] = {"resolution": res, "cases": cases,
                                                  "paper_only": [], "complete": False}
            self.save()
        self.results["sections"]["table1"] = {
            "resolution": res, "cases": cases, "complete": True,
            "paper_only": [r[0] for r in PAPER_TABLE1 if r[0] not in names]}
        self.render_table1()

    def render_table1(self):
        sec = self.results["sections"].get("table1") or {}
        cases, res = sec.get("cases", []), sec.get("resolution")
        rows = []
        for c in cases:
            r = c.get("report") or {}
            faces = get(r, "input", "faces")
            paper = self.paper_row(c["shape"], faces)
            c["paper"] = dict(zip(["name", "F", "time_s", "T", "point_size", "step"], paper)) \
                if paper else None
            p = c["paper"] or {}
            if not c["ok"]:
                rows.append([c["label"], fmt(faces), fmt(p.get("F")), failure_text(c),
                             fmt(p.get("T")), "", "", fmt(p.get("time_s"), 2), "",
                             fmt(p.get("point_size"), 4),
                             "", fmt(p.get("step"), 4), "", "", "", "", ""])
                continue
            rows.append([c["label"], fmt(faces), fmt(p.get("F")), fmt(get(r, "shell", "tets")),
                         fmt(p.get("T")), "%s (%d)" % (fmt(c["wall_s"], 2), len(c["wall_s_all"])),
                         fmt(c["timings_median_s"].get("total"), 2), fmt(p.get("time_s"), 2),
                         fmt(get(r, "trace", "point_size"), 4), fmt(p.get("point_size"), 4),
                         fmt(get(r, "trace", "step"), 4), fmt(p.get("step"), 4),
                         fmt(get(r, "shell", "coverage"), 3), fmt(get(r, "quality", "min"), 4),
                         fmt(get(r, "quality", "median"), 3)] + self.checker_cells(c) +
                        [self.largest_stage(c)])
        text = ["## Table 1 shapes at %d^3 (generated by vdb_shell_shapes)" % res, "",
                "wall s = median wall time of the vdb_shell process over the runs (count in "
                "brackets); total s = the report's timings_s.total (median); paper columns from "
                "the paper's Table 1 (its T counts 3 tets per face). checker = "
                "../shared/eval/check_shell.py --samples %d, once per shape." % self.args.samples,
                "",
                md_table(["shape", "F", "paper F", "T", "paper T", "wall s (runs)", "total s",
                          "paper s", "point size", "paper", "step", "paper", "coverage",
                          "min Q", "median Q", "checker", "checker coverage", "largest stage s"],
                         rows)]
        missing = [r for r in PAPER_TABLE1 if r[0] in sec.get("paper_only", [])]
        if missing:
            text += ["", "Paper rows without a generated shape: " + ", ".join(
                "%s (F %d, %.2f s)" % (r[0], r[1], r[2]) for r in missing) +
                " (the shared teapot.obj is another, non-watertight teapot)."]
        self.emit("\n".join(text))
        self.rendered.add("table1")
        self.save()
        self.quality_check_summary("table1")

    # -- meshes --------------------------------------------------------------------------------

    def mesh_catalog(self):
        """[(file, watertight, note)] of the --meshes folder, from its README table if any."""
        d = self.args.meshes
        if not os.path.isdir(d):
            return []
        files = sorted(f for f in os.listdir(d)
                       if os.path.splitext(f)[1].lower() in (".obj", ".off", ".ply", ".stl"))
        info = {}
        readme = os.path.join(d, "README.md")
        if os.path.exists(readme):
            with open(readme, errors="replace") as f:
                for line in f:
                    if not line.startswith("|"):
                        continue
                    cols = [c.strip() for c in line.strip().strip("|").split("|")]
                    if len(cols) < 7:
                        continue
                    m = re.match(r"^`?([^`]+)`?$", cols[0])
                    name = m.group(1) if m else cols[0]
                    if name in files:
                        wt = cols[5].strip("* ").lower()
                        info[name] = (wt == "yes", cols[-1])
        out = []
        for f in files:
            wt, note = info.get(f, (True, ""))
            out.append((f, wt, note))
        return out

    def section_meshes(self):
        catalog = self.mesh_catalog()
        if not catalog:
            self.emit("## Watertight meshes\n\nskipped: no meshes in %s." % self.args.meshes)
            return
        res = self.args.table1_resolution
        cases, skipped = [], []
        for f, watertight, note in catalog:
            label = os.path.splitext(f)[0]
            if not watertight:
                skipped.append({"file": f, "reason": "not watertight (README): " +
                                re.sub(r"\*\*", "", note)})
                continue
            log("meshes: %s @%d x%d" % (label, res, self.args.repeats))
            case = self.shell_case(label, os.path.join(self.args.meshes, f), res,
                                   self.args.repeats, "meshes")
            cases.append(case)
            self.results["sections"]["meshes"] = {"resolution": res, "cases": cases,
                                                  "skipped": skipped}
            self.save()
        self.render_meshes()

    def render_meshes(self):
        sec = self.results["sections"].get("meshes") or {}
        cases, res, skipped = sec.get("cases", []), sec.get("resolution"), sec.get("skipped", [])
        rows = []
        for c in cases:
            r = c.get("report") or {}
            if not c["ok"]:
                rows.append([c["label"], "", failure_text(c)] + [""] * 11)
                continue
            rows.append([c["label"], fmt(get(r, "input", "faces")), fmt(get(r, "shell", "tets")),
                         "%s (%d)" % (fmt(c["wall_s"], 2), len(c["wall_s_all"])),
                         fmt(c["timings_median_s"].get("total"), 2),
                         fmt(get(r, "validity", "seconds"), 2),
                         fmt(get(r, "shell", "coverage"), 3), fmt(get(r, "quality", "min"), 4),
                         fmt(get(r, "quality", "median"), 3),
                         fmt(get(r, "validity", "moved_back_vertices")),
                         fmt(kib_to_mib(c.get("maxrss_kib")), 0)] + self.checker_cells(c) +
                        [self.largest_stage(c)])
        text = ["## Watertight meshes at %d^3 (%s)" % (res, self.args.meshes), "",
                md_table(["mesh", "F", "T", "wall s (runs)", "total s", "validity s",
                          "coverage", "min Q", "median Q", "moved back", "peak MiB", "checker",
                          "checker coverage", "largest stage s"], rows)]
        if skipped:
            text += ["", "Skipped: " + "; ".join(
                "%s, %s" % (s["file"], s["reason"].split(";")[0]) for s in skipped) + "."]
        self.emit("\n".join(text))
        self.rendered.add("meshes")
        self.save()
        self.quality_check_summary("meshes")

    # -- fine meshes ---------------------------------------------------------------------------

    def fine_mesh(self, label, how, arg, n):
        """Path of one FINE_MESHES entry, made in OUT/work; (path, error)."""
        if how == "shape":
            if "shapes" not in self.bin:
                return None, "no vdb_shell_shapes"
            _, path, err = self.make_shape(arg, n)
            return path, err
        src = os.path.join(self.args.meshes, arg)
        path = os.path.join(self.work, label + ".obj")
        if not os.path.exists(src):
            return None, "%s not found" % src
        if not os.path.exists(path):
            if "fields_bench" not in self.bin:
                return None, "no vdb_shell_bench_fields"
            rec = self.runner.run([self.bin["fields_bench"], "--write-subdivided", src, path,
                                   "--levels", n])
            if not rec["ok"]:
                return None, rec["error"]
        return path, None

    def section_fine(self):
        res = self.args.table1_resolution
        cases = []
        self.results["sections"]["fine"] = {"resolution": res, "cases": cases}
        for label, how, arg, n in FINE_MESHES:
            path, err = self.fine_mesh(label, how, arg, n)
            if path is None:
                log("fine: %s: %s" % (label, err))
                cases.append({"label": label, "ok": False, "error": err, "runs": []})
                continue
            log("fine: %s @%d x%d" % (label, res, self.args.fine_repeats))
            case = self.shell_case(label, path, res, self.args.fine_repeats, "fine",
                                   checker=True, verify_quality=False, keep_shell=False)
            cases.append(case)
            self.save()
        self.render_fine()

    def render_fine(self):
        sec = self.results["sections"].get("fine") or {}
        rows = []
        for c in sec.get("cases", []):
            if not c.get("ok"):
                rows.append([c["label"]] + [""] * 11 + [failure_text(c)])
                continue
            r, t = c["report"], c["timings_median_s"]
            samples = get(r, "trace", "samples")
            stops = r.get("stop_reasons") or {}
            per_sample = t["trace"] / samples * 1e6 if samples and t.get("trace") else None
            rows.append([c["label"], fmt(get(r, "input", "faces")), len(c["wall_s_all"]),
                         fmt(t.get("fields"), 2), fmt(t.get("trace"), 2),
                         fmt(t.get("assemble"), 2), fmt(t.get("check"), 2),
                         fmt(t.get("total"), 2), fmt(samples),
                         fmt(per_sample, 2),
                         "/".join(str(stops.get(k, "")) for k in
                                  ("critical", "merge", "flux", "cap")),
                         fmt(get(r, "shell", "coverage"), 3), self.checker_cells(c)[0]])
        text = ["## Fine meshes at %s^3" % sec.get("resolution"), "",
                "Meshes much finer than the grid (the report's timings_s, median over the runs, "
                "all threads; us/sample: trace wall seconds per trace sample; stops: critical/"
                "merge/flux/cap; checker: ../shared/eval/check_shell.py).", "",
                md_table(["mesh", "F", "runs", "fields s", "trace s", "assemble s", "check s",
                          "total s", "samples", "us/sample", "stops", "coverage", "checker"],
                         rows)]
        self.emit("\n".join(text))
        self.rendered.add("fine")
        self.save()

    # -- layers --------------------------------------------------------------------------------

    def section_layers(self):
        res = self.args.table1_resolution
        meshes = [(label, os.path.join(self.args.meshes, f)) for label, f in LAYER_MESHES
                  if os.path.exists(os.path.join(self.args.meshes, f))]
        if "shapes" in self.bin:
            label, path, err = self.make_shape("sphere", 2)
            if path:
                meshes.append((label, path))
        cases = []
        self.results["sections"]["layers"] = {"resolution": res, "cases": cases}
        for label, path in meshes:
            for layers, ratio in LAYER_CASES:
                name = "%s_K%d_r%g" % (label, layers, ratio)
                log("layers: %s @%d x%d" % (name, res, self.args.repeats))
                case = self.shell_case(name, path, res, self.args.repeats, "layers",
                                       verify_quality=False, keep_shell=False,
                                       extra=["--layers", layers, "--layer-ratio", ratio])
                case.update({"mesh": label, "layers": layers, "ratio": ratio})
                cases.append(case)
                self.save()
        self.render_layers()

    def render_layers(self):
        sec = self.results["sections"].get("layers") or {}
        rows = []
        for c in sec.get("cases", []):
            if not c.get("ok"):
                rows.append([c.get("mesh", c["label"]), c.get("layers"), c.get("ratio")] +
                            [""] * 9 + [failure_text(c)])
                continue
            r, t = c["report"], c["timings_median_s"]
            rows.append([c["mesh"], c["layers"], fmt(c["ratio"], 2),
                         fmt(get(r, "shell", "tets")), fmt(get(r, "shell", "coverage"), 3),
                         fmt(get(r, "quality", "min"), 5), fmt(get(r, "quality", "p5"), 3),
                         fmt(get(r, "quality", "median"), 3),
                         fmt(get(r, "quality", "min_dihedral_deg"), 3),
                         fmt(t.get("assemble"), 2), fmt(t.get("total"), 2),
                         fmt(kib_to_mib(c.get("maxrss_kib")), 0), self.checker_cells(c)[0]])
        text = ["## Layers at %s^3" % sec.get("resolution"), "",
                "--layers K --layer-ratio r (validity: the report's assemble stage, the search "
                "and its final check; seconds are medians over the runs; checker: "
                "../shared/eval/check_shell.py).", "",
                md_table(["mesh", "K", "r", "tets", "coverage", "min Q", "Q p5", "Q median",
                          "min dihedral", "validity s", "total s", "peak MiB", "checker"], rows)]
        self.emit("\n".join(text))
        self.rendered.add("layers")
        self.save()

    # -- scaling meshes ------------------------------------------------------------------------

    def scaling_meshes(self):
        """[(label, path)] of --scaling-meshes; fertility_x16 is written into OUT/work."""
        meshes = []
        for name in self.args.scaling_meshes:
            if name == "fandisk":
                path = os.path.join(self.args.meshes, "fandisk.obj")
            elif name == "fertility_x16":
                path = os.path.join(self.work, "fertility_x16.obj")
                fert = os.path.join(self.args.meshes, "fertility.off")
                if not os.path.exists(path) and os.path.exists(fert) and \
                        "fields_bench" in self.bin:
                    rec = self.runner.run([self.bin["fields_bench"], "--write-subdivided", fert,
                                           path, "--levels", 2])
                    if not rec["ok"]:
                        log("writing fertility x16 failed: %s" % rec["error"])
                if not os.path.exists(path) and "shapes" in self.bin:
                    log("no fertility x16: using the 101,568-face box (detail 46) instead")
                    name, path, _ = self.make_shape("box", 46)
            else:
                path = os.path.abspath(name)
                name = os.path.splitext(os.path.basename(name))[0]
            if path and os.path.exists(path):
                meshes.append((name, path))
            else:
                log("scaling: no surface for %s" % name)
        return meshes

    def count_faces(self, path):
        try:
            return int(len(read_surface(path)[1]))
        except (OSError, ValueError, IndexError):
            return None

    def floor_run(self, mesh, res, threads=None):
        cmd = [self.bin["fields_bench"], "--floor", mesh, "--resolution", res, "--json"]
        if threads:
            cmd += ["--threads", threads]
        rec = self.runner.run(cmd, keep_stdout=True)
        if rec["ok"]:
            try:
                rec["floor"] = json.loads(rec["stdout"].strip().splitlines()[-1])
            except (ValueError, IndexError) as e:
                rec["ok"], rec["error"] = False, "unreadable floor JSON: %s" % e
        rec.pop("stdout", None)
        return rec

    def section_scaling(self):
        if "fields_bench" not in self.bin:
            self.emit("## Scaling\n\nskipped: no vdb_shell_bench_fields in the build folder.")
            return
        meshes = self.scaling_meshes()
        cases = []
        self.results["sections"]["scaling"] = {"cases": cases, "skipped": []}
        for label, path in meshes:
            timed_out_at = None
            faces = self.count_faces(path)
            for res in self.args.resolutions:
                if timed_out_at is not None and not self.args.continue_after_timeout:
                    self.results["sections"]["scaling"]["skipped"].append(
                        "%s at %d (timed out at %d; --continue-after-timeout runs it)"
                        % (label, res, timed_out_at))
                    continue
                n = self.args.scaling_repeats if res <= self.args.scaling_single_above else 1
                log("scaling: %s @%d x%d (floor and shell alternating)" % (label, res, n))
                floors, case = [], None
                runs = []
                for k in range(n):
                    floors.append(self.floor_run(path, res))
                    c = self.shell_case(label, path, res, 1, "scaling", checker=False,
                                        verify_quality=False, keep_shell=self.args.keep)
                    runs += c["runs"]
                    if not c["ok"]:
                        if c["runs"] and c["runs"][-1].get("timed_out"):
                            timed_out_at = res
                        break
                    if not self.affordable(c["runs"][-1]) and k + 1 < n:
                        log("  one run took %.0f s: no more repeats (--affordable-s %g)"
                            % (c["runs"][-1]["wall_s"], self.args.affordable_s))
                        break
                case = {"label": label, "surface": path, "resolution": res, "runs": runs,
                        "threads": None, "faces": faces}
                self.summarize_case(case)
                ok_floors = [f for f in floors if f["ok"]]
                case["floor_runs"] = floors
                case["floor_s"] = median([get(f, "floor", "floor_s") for f in ok_floors])
                case["floor_wall_s"] = median([f["wall_s"] for f in ok_floors])
                case["floor_maxrss_kib"] = median([f["maxrss_kib"] for f in ok_floors])
                case["floor_error"] = None if ok_floors else (
                    floors[0]["error"] if floors else "not run")
                tot = (case.get("timings_median_s") or {}).get("total")
                fld = (case.get("timings_median_s") or {}).get("fields")
                floor_s = case["floor_s"]
                case["ratio_total_floor"] = tot / floor_s if tot and floor_s else None
                case["ratio_fields_floor"] = fld / floor_s if fld and floor_s else None
                cases.append(case)
                self.save()
        self.render_scaling()

    def render_scaling(self):
        sec = self.results["sections"].get("scaling") or {}
        cases = sec.get("cases", [])
        stages = []
        for c in cases:
            for s in c.get("stages") or []:
                if s != "total" and s not in stages:
                    stages.append(s)
        rows = []
        for c in cases:
            r = c.get("report") or {}
            t = c.get("timings_median_s") or {}
            floor = fmt(c["floor_s"], 2) if c["floor_s"] is not None else \
                failure_text({"error": c["floor_error"]})
            if not c["ok"]:
                rows.append([c["label"], fmt(c.get("faces")), c["resolution"], len(c["runs"])] +
                            [""] * len(stages)
                            + [failure_text(c), "", "", floor,
                               fmt(kib_to_mib(c["floor_maxrss_kib"]), 0), "", ""])
                continue
            rows.append([c["label"], fmt(get(r, "input", "faces")), c["resolution"],
                         len(c["wall_s_all"])] + [fmt(t.get(s), 2) for s in stages] +
                        [fmt(t.get("total"), 2), fmt(c["wall_s"], 2),
                         fmt(kib_to_mib(c["maxrss_kib"]), 0), floor,
                         fmt(kib_to_mib(c["floor_maxrss_kib"]), 0),
                         ratio_text(c["ratio_total_floor"]), ratio_text(c["ratio_fields_floor"])])
        text = ["## Scaling: time per stage, peak memory, ratio to the meshToLevelSet floor", "",
                "Stage columns: the report's timings_s (median over the runs, all threads); "
                "peak MiB: the process's maximum RSS (wait4). floor: vdb_shell_bench_fields "
                "--floor (OpenVDB meshToLevelSet, half-width 3, same mesh and resolution, run "
                "alternately with vdb_shell); ratios: total / floor and fields / floor.",
                "", md_table(["mesh", "F", "res", "runs"] + ["%s s" % s for s in stages] +
                             ["total s", "wall s", "peak MiB", "floor s", "floor peak MiB",
                              "total/floor", "fields/floor"], rows)]
        if sec.get("skipped"):
            text += ["", "Not run: " + "; ".join(sec["skipped"]) + "."]
        self.emit("\n".join(text))
        self.rendered.add("scaling")
        self.save()

    # -- threads -------------------------------------------------------------------------------

    def section_threads(self):
        meshes = self.scaling_meshes()
        res = self.args.thread_resolution
        cases = []
        self.results["sections"]["threads"] = {"resolution": res, "cases": cases}
        for label, path in meshes:
            log("threads: %s @%d, -j 1 / -j 2 x%d" % (label, res, self.args.thread_repeats))
            runs = {1: [], 2: []}
            stop = False
            for k in range(self.args.thread_repeats):
                for j in (1, 2):
                    c = self.shell_case(label + "_j%d" % j, path, res, 1, "threads", threads=j,
                                        checker=False, verify_quality=False,
                                        keep_shell=self.args.keep)
                    runs[j] += c["runs"]
                    last = c["runs"][-1] if c["runs"] else {}
                    if not c["ok"]:
                        stop = True
                        break
                    if not self.affordable(last) and k + 1 < self.args.thread_repeats:
                        log("  one run took %.0f s: no more repeats (--affordable-s %g)"
                            % (last["wall_s"], self.args.affordable_s))
                        stop = True
                if stop:
                    break
            per = {}
            for j in (1, 2):
                cj = {"label": label, "runs": runs[j]}
                self.summarize_case(cj)
                per[j] = cj
            stages = [s for s in per[1].get("stages") or [] if s in (per[2].get("stages") or [])]
            speedup = {}
            if per[1]["ok"] and per[2]["ok"]:
                for s in stages:
                    a, b = per[1]["timings_median_s"].get(s), per[2]["timings_median_s"].get(s)
                    speedup[s] = a / b if a and b else None
                speedup["wall"] = per[1]["wall_s"] / per[2]["wall_s"]
            cases.append({"label": label, "surface": path, "resolution": res,
                          "faces": get(per[1].get("report") or per[2].get("report") or {},
                                       "input", "faces") or self.count_faces(path),
                          "stages": stages, "one_thread": per[1], "two_threads": per[2],
                          "speedup": speedup})
            self.save()
        self.render_threads()

    def render_threads(self):
        sec = self.results["sections"].get("threads") or {}
        cases, res = sec.get("cases", []), sec.get("resolution")
        stages = []
        for c in cases:
            for s in c["stages"]:
                if s not in stages:
                    stages.append(s)
        rows = []
        for c in cases:
            for j, key in ((1, "one_thread"), (2, "two_threads")):
                p = c[key]
                if not p["ok"]:
                    rows.append([c["label"], fmt(c["faces"]), res, "-j %d" % j, len(p["runs"]),
                                 failure_text(p)] + [""] * len(stages))
                    continue
                t = p["timings_median_s"]
                rows.append([c["label"], fmt(c["faces"]), res, "-j %d" % j, len(p["wall_s_all"])]
                            + [fmt(t.get(s), 3) for s in stages] + [fmt(p["wall_s"], 2)])
            if c["speedup"]:
                rows.append([c["label"], "", res, "speed-up", ""] +
                            [("%sx" % fmt(c["speedup"].get(s), 2)) if c["speedup"].get(s)
                             else "" for s in stages] +
                            ["%sx" % fmt(c["speedup"].get("wall"), 2)])
        text = ["## Threads: 1 vs 2 (-j 1 / -j 2, alternating, medians)", "",
                "Stage columns: the report's timings_s; speed-up = 1-thread median / 2-thread "
                "median. Meaningful only with a free second core (see the load average).", "",
                md_table(["mesh", "F", "res", "threads", "runs"] + ["%s s" % s for s in stages] +
                         ["wall s"], rows)]
        self.emit("\n".join(text))
        self.rendered.add("threads")
        self.save()

    # -- peers ---------------------------------------------------------------------------------

    def tetgen_run(self, label, surface, flags):
        d = os.path.join(self.work, "tetgen")
        os.makedirs(d, exist_ok=True)
        stem = "%s_%s" % (label, flags.strip("-"))
        off = os.path.join(d, stem + ".off")
        try:
            pts, tris = read_surface(surface)
            write_off(off, pts, tris)
            self.surface_faces[label] = len(tris)
        except (OSError, ValueError) as e:
            return {"ok": False, "error": "cannot convert to OFF: %s" % e, "flags": flags}
        for ext in (".1.node", ".1.ele", ".1.face", ".1.edge", ".1.neigh"):
            if os.path.exists(os.path.join(d, stem + ext)):
                os.remove(os.path.join(d, stem + ext))
        rec = self.runner.run([self.bin["tetgen"], flags, off], cwd=d)
        rec["flags"] = flags
        if rec["ok"]:
            try:
                p, t = read_tetgen(os.path.join(d, stem + ".1"))
                q = tet_quality(p, t)
                flipped = bool(len(q)) and bool(np.sum(q < 0) > np.sum(q > 0))
                if flipped:  # the other orientation convention: compare like with like
                    t = t[:, [0, 1, 3, 2]]
                    q = -q
                rec["orientation_flipped"] = flipped
                rec["quality"] = quality_summary(q)
                rec["tets"] = rec["quality"]["tets"]
            except (OSError, ValueError, IndexError) as e:
                rec["ok"], rec["error"] = False, "cannot read TetGen output: %s" % e
        if not self.args.keep:
            for ext in (".1.node", ".1.ele", ".1.face", ".1.edge", ".1.neigh", ".off"):
                path = os.path.join(d, stem + ext)
                if os.path.exists(path):
                    os.remove(path)
        return rec

    def section_peers(self):
        if "tetgen" not in self.bin:
            self.emit("## Peers: TetGen\n\nskipped: no tetgen on PATH (apt-get install tetgen; "
                      "scripts/install-deps.sh lists it).")
            return
        surfaces = []
        for sec in ("table1", "meshes"):
            for c in (self.results["sections"].get(sec) or {}).get("cases", []):
                if c.get("surface"):
                    surfaces.append((c["label"], c["surface"], c))
        if not surfaces:  # table1/meshes not selected: the same surfaces, vdb_shell run once
            if "shapes" in self.bin:
                for name, detail in self.table1_jobs([n for n, _ in self.shape_list()]):
                    label, path, _ = self.make_shape(name, detail)
                    if path:
                        surfaces.append((label, path, None))
            for f, wt, _ in self.mesh_catalog():
                if wt:
                    surfaces.append((os.path.splitext(f)[0], os.path.join(self.args.meshes, f),
                                     None))
        res = self.args.table1_resolution
        cases = []
        for label, surface, vcase in surfaces:
            if vcase is None:
                log("peers: vdb_shell %s @%d" % (label, res))
                vcase = self.shell_case(label, surface, res, 1, "peers", checker=False)
            entry = {"label": label, "surface": surface, "vdb_shell": {
                "ok": vcase.get("ok"), "error": vcase.get("error"),
                "wall_s": vcase.get("wall_s"),
                "tets": get(vcase.get("report") or {}, "shell", "tets"),
                "faces": get(vcase.get("report") or {}, "input", "faces"),
                "min": get(vcase.get("report") or {}, "quality", "min"),
                "median": get(vcase.get("report") or {}, "quality", "median"),
                "maxrss_kib": vcase.get("maxrss_kib")}, "tetgen": []}
            for flags in self.args.tetgen_flags:
                log("peers: tetgen %s %s" % (flags, label))
                entry["tetgen"].append(self.tetgen_run(label, surface, flags))
            cases.append(entry)
            self.results["sections"]["peers"] = {"resolution": res, "cases": cases}
            self.save()
        self.render_peers()

    def render_peers(self):
        sec = self.results["sections"].get("peers") or {}
        cases, res = sec.get("cases", []), sec.get("resolution")
        rows = []
        for e in cases:
            v = e["vdb_shell"]
            faces = fmt(v["faces"] or self.surface_faces.get(e["label"]))
            if v["ok"]:
                rows.append([e["label"], faces, "vdb_shell %d^3" % res, fmt(v["tets"]),
                             fmt(v["wall_s"], 2), fmt(v["min"], 4), fmt(v["median"], 3),
                             fmt(kib_to_mib(v["maxrss_kib"]), 0)])
            else:
                rows.append([e["label"], faces, "vdb_shell", failure_text(v), "", "", "", ""])
            for t in e["tetgen"]:
                name = "tetgen %s" % t["flags"]
                if t["ok"]:
                    q = t["quality"]
                    rows.append([e["label"], faces, name, fmt(t["tets"]), fmt(t["wall_s"], 2),
                                 fmt(q["min"], 4), fmt(q["median"], 3),
                                 fmt(kib_to_mib(t["maxrss_kib"]), 0)])
                else:
                    rows.append([e["label"], faces, name, failure_text(t), "", "", "", ""])
        text = ["## Peers: TetGen on the same surfaces", "",
                "time s: wall time of the process (vdb_shell: median over its runs; TetGen: one "
                "run, including its file output). Q: volume-length ratio 6 sqrt(2) V / l_rms^3, "
                "computed here for TetGen with vdb_shell's formula (core/assemble/quality.cpp), "
                "which is checked against vdb_shell's own reports (quality formula check lines).",
                "",
                md_table(["mesh", "F", "method", "T", "time s", "min Q", "median Q", "peak MiB"],
                         rows)]
        self.emit("\n".join(text))
        self.rendered.add("peers")
        self.save()

    # -- quality formula check -----------------------------------------------------------------

    def quality_check_summary(self, sec):
        checks = []
        for c in (self.results["sections"].get(sec) or {}).get("cases", []):
            if c.get("quality_check"):
                checks.append((c["label"], c["quality_check"]))
        if not checks:
            return
        good = [l for l, q in checks if q.get("match")]
        diffs = []
        for _, q in checks:
            for a, b in (("python_min", "report_min"), ("python_median", "report_median")):
                if q.get(a) is not None and q.get(b) is not None:
                    diffs.append(abs(q[a] - q[b]))
        bad = ["%s (%s)" % (l, q.get("error") or "min %s vs %s, median %s vs %s" % (
            q.get("python_min"), q.get("report_min"), q.get("python_median"),
            q.get("report_median"))) for l, q in checks if not q.get("match")]
        text = ("Quality formula check (numpy on the written .vtu vs the report's quality.min / "
                "quality.median): %d of %d shells match, largest difference %s."
                % (len(good), len(checks), "%.1e" % max(diffs) if diffs else "n/a"))
        if bad:
            text += " Mismatch: " + "; ".join(bad)
        self.results["sections"][sec]["quality_formula_check"] = {
            "shells": len(checks), "match": len(good),
            "max_abs_difference": max(diffs) if diffs else None, "mismatches": bad}
        self.emit(text)

    # -- targets -------------------------------------------------------------------------------

    def section_targets(self):
        rows, raw = [], []

        def add(target, measured, limit, met, margin, status=None):
            status = status or ("not measured" if met is None else ("met" if met else "MISSED"))
            rows.append([target, measured, limit, status, margin])
            raw.append({"target": target, "measured": measured, "limit": limit,
                        "status": status, "margin": margin})

        t1 = self.results["sections"].get("table1")
        if t1 and t1.get("cases"):
            # only the shapes of the paper's Table 1 (not e.g. torus)
            cases = [c for c in t1["cases"] if self.paper_row(c.get("shape"), get(
                c.get("report") or {}, "input", "faces") or 10 ** 9)]
            ok = [c for c in cases if c.get("ok")]
            failed = [c["label"] for c in cases if not c.get("ok")]
            over = [c for c in ok if c["wall_s"] > TARGET_TABLE1_S]
            worst = max(ok, key=lambda c: c["wall_s"]) if ok else None
            measured = ("worst %s %.2f s; %d of %d shapes <= %.1f s" % (
                worst["label"], worst["wall_s"], len(ok) - len(over), len(cases),
                TARGET_TABLE1_S)) if worst else "no successful run"
            if failed:
                measured += "; failed: " + ", ".join(failed)
            margin = ("over by %.2f s (%s)" % (worst["wall_s"] - TARGET_TABLE1_S, ", ".join(
                "%s %.2f" % (c["label"], c["wall_s"]) for c in over))) if over else (
                "%.2f s to spare" % (TARGET_TABLE1_S - worst["wall_s"]) if worst else "")
            add("Table 1 shapes end-to-end at %d^3 (median wall)" % t1["resolution"], measured,
                "<= %.1f s each" % TARGET_TABLE1_S,
                None if not ok else (not over and not failed), margin)
        else:
            add("Table 1 shapes end-to-end at 128^3", "", "<= %.1f s each" % TARGET_TABLE1_S, None,
                "section not run")

        fine = (self.results["sections"].get("fine") or {}).get("cases", [])
        sphere = next((c for c in fine if c["label"] == "sphere-d8"), None)
        if sphere and sphere.get("ok"):
            tot = sphere["timings_median_s"]["total"]
            add("50,880-face sphere at 128^3: whole run", "%.2f s (trace %.2f s)" % (
                tot, sphere["timings_median_s"]["trace"]), "<= %.0f s" % TARGET_FINE_SPHERE_S,
                tot <= TARGET_FINE_SPHERE_S, "%.2f s %s" % (abs(TARGET_FINE_SPHERE_S - tot),
                                                            "to spare" if tot <= TARGET_FINE_SPHERE_S
                                                            else "over"))
        else:
            add("50,880-face sphere at 128^3: whole run", failure_text(sphere) if sphere else "",
                "<= %.0f s" % TARGET_FINE_SPHERE_S, None, "" if sphere else "fine not run")
        for label, limit, stands_for in TARGET_FINE_RUNS:
            c = next((c for c in fine if c["label"] == label), None)
            name = "%s at 128^3: whole run (for %s)" % (label, stands_for)
            if c and c.get("ok"):
                tot = c["timings_median_s"]["total"]
                add(name, "%.2f s (assemble %.2f s)" % (tot, c["timings_median_s"]["assemble"]),
                    "<= %.0f s" % limit, tot <= limit,
                    "%.2f s %s" % (abs(limit - tot), "to spare" if tot <= limit else "over"))
            else:
                add(name, failure_text(c) if c else "", "<= %.0f s" % limit, None,
                    "" if c else "fine not run")

        sc = (self.results["sections"].get("scaling") or {}).get("cases", [])
        at512 = [c for c in sc if c["resolution"] == 512]
        if at512:
            for c in at512:
                r = c.get("ratio_total_floor")
                add("%s at 512^3: total / floor" % c["label"],
                    ("%.2fx (%.2f s / %.2f s)" % (r, c["timings_median_s"]["total"], c["floor_s"])
                     if r else failure_text(c) if not c.get("ok") else "no floor"),
                    "<= %.1fx" % TARGET_FLOOR_RATIO_512, None if r is None else
                    r <= TARGET_FLOOR_RATIO_512,
                    "" if r is None else ("%.2fx over" % (r - TARGET_FLOOR_RATIO_512)
                                          if r > TARGET_FLOOR_RATIO_512 else
                                          "%.2fx to spare" % (TARGET_FLOOR_RATIO_512 - r)))
        else:
            add("512^3: total / floor", "", "<= 2x", None,
                "512 not in --resolutions" if "scaling" in self.args.sections
                else "scaling not run")
        big_meshes = [c["label"] for c in sc if (c.get("faces") or 0) >= 100000]
        big_meshes = sorted(set(big_meshes), key=big_meshes.index)
        skipped = (self.results["sections"].get("scaling") or {}).get("skipped", [])
        for label in big_meshes or [">= 100k-face mesh"]:
            c = next((c for c in sc if c["label"] == label and c["resolution"] == 1024), None)
            if c is None:
                why = next((x for x in skipped if x.startswith(label + " at 1024")), None)
                add("%s at 1024^3: time and peak" % label, why or "",
                    "<= %.0f s, <= %.0f GiB" % (TARGET_1024_S, TARGET_1024_PEAK_KIB / 1048576.0),
                    None, "not run" if why else "scaling not run"
                    if "scaling" not in self.args.sections
                    else "1024 not in --resolutions or no such mesh")
                continue
            if not c.get("ok"):
                timed_out = any(r.get("timed_out") for r in c["runs"])
                add("%s at 1024^3: end-to-end time" % label, failure_text(c),
                    "<= %.0f s" % TARGET_1024_S, False if timed_out else None,
                    "over by > %.0f s" % (self.args.timeout - TARGET_1024_S) if timed_out
                    else "", status=None if timed_out else "failed")
                continue
            tot = c["timings_median_s"].get("total")
            w = c["wall_s"]
            add("%s at 1024^3: end-to-end time" % label,
                "%.1f s wall (total %.1f s)" % (w, tot), "<= %.0f s" % TARGET_1024_S,
                w <= TARGET_1024_S, ("%.1f s over" % (w - TARGET_1024_S)) if w > TARGET_1024_S
                else "%.1f s to spare" % (TARGET_1024_S - w))
            pk = c["maxrss_kib"]
            add("%s at 1024^3: peak memory" % label,
                "%.0f MiB" % (pk / 1024.0),
                "<= %.0f GiB (%.0f MiB)" % (TARGET_1024_PEAK_KIB / 1048576.0,
                                            TARGET_1024_PEAK_KIB / 1024.0),
                pk <= TARGET_1024_PEAK_KIB,
                ("%.0f MiB over" % ((pk - TARGET_1024_PEAK_KIB) / 1024.0))
                if pk > TARGET_1024_PEAK_KIB else
                "%.0f MiB to spare" % ((TARGET_1024_PEAK_KIB - pk) / 1024.0))
        th = (self.results["sections"].get("threads") or {}).get("cases", [])
        for c in th:
            bad = next((c[k] for k in ("one_thread", "two_threads") if not c[k]["ok"]), None)
            for stage in ("trace", "assemble"):
                s = c["speedup"].get(stage) if c["speedup"] else None
                add("%s at %d^3: %s speed-up 1 -> 2 threads" % (c["label"], c["resolution"], stage),
                    "%.2fx" % s if s else failure_text(bad) if bad else "no %s stage" % stage,
                    ">= %.1fx" % TARGET_SPEEDUP, None if s is None else s >= TARGET_SPEEDUP,
                    "" if s is None else ("%.2fx short" % (TARGET_SPEEDUP - s) if s < TARGET_SPEEDUP
                                          else "%.2fx to spare" % (s - TARGET_SPEEDUP)),
                    status="failed" if bad else None)
        if not th:
            add("trace and assemble speed-up 1 -> 2 threads", "", ">= %.1fx" % TARGET_SPEEDUP, None,
                "threads not run")
        text = ["## Targets (reported, never asserted)", "",
                md_table(["target", "measured", "limit", "status", "margin"], rows)]
        if self.args.quick:
            text += ["", "--quick: low resolutions and single runs; not a measurement of the "
                     "targets."]
        self.emit("\n".join(text))
        self.results["targets"] = raw


# ----------------------------------------------------------------------------------------------


def parse_args(argv):
    ap = argparse.ArgumentParser(
        description="vdb_shell benchmark suite: Markdown tables on stdout, OUT/results.md and "
                    "OUT/results.json. See docs/benchmarks.md.")
    ap.add_argument("--build", default="build", help="CMake build folder (default: build)")
    ap.add_argument("--out", default="/tmp/vdb_shell-bench",
                    help="output folder: results.md, results.json, work/ (generated shapes, "
                         "shells, reports); created if missing; keep it outside the checkout "
                         "(default: /tmp/vdb_shell-bench)")
    ap.add_argument("--quick", action="store_true",
                    help="1 run per point, low resolutions, fandisk only for scaling/threads (1-2 "
                         "minutes): for trying the driver out, not for numbers")
    ap.add_argument("--sections", default=",".join(ALL_SECTIONS),
                    help="comma-separated subset of %s (default: all)" % ",".join(ALL_SECTIONS))
    ap.add_argument("--timeout", type=float, default=900.0,
                    help="seconds per child process before it is killed and recorded as failed "
                         "(default 900)")
    ap.add_argument("--repeats", type=int, default=None,
                    help="runs per shape in table1/meshes, median reported (default 5; quick 1)")
    ap.add_argument("--table1-resolution", type=int, default=128,
                    help="resolution of table1, meshes and peers (default 128, also in --quick)")
    ap.add_argument("--resolutions", default=None,
                    help="scaling resolutions (default 128,256,512,1024; quick 64,128)")
    ap.add_argument("--fine-repeats", type=int, default=None,
                    help="runs per mesh in the fine section (default 1)")
    ap.add_argument("--scaling-repeats", type=int, default=None,
                    help="runs per scaling point (default 3; quick 1)")
    ap.add_argument("--scaling-single-above", type=int, default=512,
                    help="scaling resolutions above this run once (default 512)")
    ap.add_argument("--scaling-meshes", default=None,
                    help="comma-separated: fandisk, fertility_x16 (fertility.off subdivided "
                         "twice, 144,000 faces, written into OUT/work) or paths of surface files "
                         "(default fandisk,fertility_x16; quick fandisk)")
    ap.add_argument("--continue-after-timeout", action="store_true",
                    help="scaling: run the higher resolutions of a mesh that timed out (by "
                         "default they are skipped and listed)")
    ap.add_argument("--affordable-s", type=float, default=120.0,
                    help="scaling/threads: no further repeats of a point once one run took "
                         "longer than this (default 120 s)")
    ap.add_argument("--thread-resolution", type=int, default=None,
                    help="resolution of the threads section (default 512; quick 128)")
    ap.add_argument("--thread-repeats", type=int, default=None,
                    help="runs per thread count (default 3; quick 1)")
    ap.add_argument("--meshes", default=os.path.join(SHARED, "meshes"),
                    help="folder of real surface meshes (default ../shared/meshes)")
    ap.add_argument("--checker", default=os.path.join(SHARED, "eval", "check_shell.py"),
                    help="independent checker script (default ../shared/eval/check_shell.py)")
    ap.add_argument("--samples", type=int, default=50000,
                    help="checker --samples (default 50000)")
    ap.add_argument("--no-checker", action="store_true", help="do not run the checker")
    ap.add_argument("--python", default="/usr/bin/python3" if os.path.exists("/usr/bin/python3")
                    else sys.executable, help="interpreter for the checker (default "
                    "/usr/bin/python3)")
    ap.add_argument("--tetgen", default=None, help="tetgen binary (default: tetgen on PATH)")
    ap.add_argument("--tetgen-flags", default="-pQ,-pqQ",
                    help="comma-separated TetGen switch sets (default -pQ,-pqQ)")
    ap.add_argument("--keep", action="store_true",
                    help="keep the large shells of scaling/threads and TetGen's output files")
    a = ap.parse_args(argv)
    a.sections = [s.strip() for s in a.sections.split(",") if s.strip()]
    unknown = [s for s in a.sections if s not in ALL_SECTIONS]
    if unknown:
        ap.error("unknown section(s) %s; known: %s" % (", ".join(unknown),
                                                         ", ".join(ALL_SECTIONS)))
    q = a.quick
    a.repeats = a.repeats or (1 if q else 5)
    a.scaling_repeats = a.scaling_repeats or (1 if q else 3)
    a.fine_repeats = a.fine_repeats or 1
    a.thread_repeats = a.thread_repeats or (1 if q else 3)
    a.thread_resolution = a.thread_resolution or (128 if q else 512)
    a.resolutions = [int(x) for x in (a.resolutions or ("64,128" if q else "128,256,512,1024"))
                     .split(",") if x.strip()]
    a.tetgen_flags = [f.strip() for f in a.tetgen_flags.split(",") if f.strip()]
    a.scaling_meshes = [m.strip() for m in (a.scaling_meshes or (
        "fandisk" if q else "fandisk,fertility_x16")).split(",") if m.strip()]
    a.meshes = os.path.abspath(a.meshes)
    return a


def main(argv):
    args = parse_args(argv)
    out = os.path.abspath(args.out)
    if os.path.commonpath([out, REPO]) == REPO:
        log("note: --out %s is inside the repository; its files are not ignored by git" % out)
    suite = Suite(args)
    suite.find_binaries()
    t0 = time.time()

    def on_term(signum, frame):  # make SIGTERM behave like Ctrl-C: kill the child, save
        raise KeyboardInterrupt

    signal.signal(signal.SIGTERM, on_term)
    suite.machine("start")
    suite.emit("# vdb_shell benchmarks%s\n\n%s" % (" (--quick)" if args.quick else "",
                                                    suite.machine_markdown()))
    interrupted = False
    try:
        for name in args.sections:
            log("section %s" % name)
            getattr(suite, "section_" + name)()
    except KeyboardInterrupt:
        interrupted = True
        log("interrupted: writing what was measured")
        for name in args.sections:  # the partial tables of the interrupted section
            if suite.results["sections"].get(name, {}).get("cases") and \
                    name not in suite.rendered:
                getattr(suite, "render_" + name)()
    suite.section_targets()
    suite.machine("end")
    suite.markdown[0] = "# vdb_shell benchmarks%s\n\n%s" % (
        " (--quick)" if args.quick else "", suite.machine_markdown())
    m = suite.results["machine"]
    suite.emit("Load average at the end: %s (start %s). Suite time: %.0f s.%s" % (
        " ".join(str(x) for x in m.get("load_average_end", [])),
        " ".join(str(x) for x in m.get("load_average_start", [])), time.time() - t0,
        " INTERRUPTED." if interrupted else ""))
    suite.results["suite_seconds"] = time.time() - t0
    suite.results["interrupted"] = interrupted
    suite.save()
    suite.runner.close()
    log("wrote %s and %s" % (os.path.join(suite.out, "results.md"),
                             os.path.join(suite.out, "results.json")))
    return 130 if interrupted else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
