"""Cost of the web viewer (issue 13): throughput with one browser connected, and the update latency to it.

Usage: .venv/bin/python bench/viewer_overhead.py [WORLD] [--steps N] [--rounds R] [--rate HZ] [--realtime S]
                                               [--no-pin] [--viewer-cpu 0|1] [--controller AGENT=CONTROLLER]
                                               [--chromedriver PATH] [--smoke]
       --smoke: 1 round of 200 steps and 2 s at real time, to check that the bench runs (tests/bench).

WORLD (default worlds/cleanup.xml) runs with the scripted robot (``robot_000=cleanup.robot``) so that it moves.
One simulation per condition below is built, and all are advanced in lockstep, the same N steps each per round, by
``sigcore.sim.run`` as fast as possible (MuJoCo is deterministic: each round they do the same physics in the same
phase of the task); the order of the conditions changes every round. One :class:`sigcore_viewer.WebViewer`
(``rate`` Hz) per viewer condition, each on its own simulation, is started once; a headless Chromium 1280x800
(software WebGL: SwiftShader, no GPU) opens viewer A, another viewer C (with ``--no-pin`` a third one viewer B), and
each stays connected for the whole bench. A browser that is not part of a condition is frozen (SIGSTOP) while it
runs, so that it takes no CPU; between rounds every browser runs.

CPU pinning (the default): on the user's machine the browser runs on the user's computer, not on the simulation's
cores. To model that on one machine, this process (every thread: the simulation's) is pinned to CPU 0 from the start
of ``main``; every process of every browser (chromedriver and all its descendants, every thread of each) to CPU 1,
right after the driver started and again before every round (Chromium starts new processes); the viewers' own
processes (viser's server and the push thread, ``sigcore_viewer.front``) to ``--viewer-cpu``: by default CPU 1, the
machine's other core (the simulation uses one core; the viewer's process is what a second core of the simulation's
machine runs), with ``--viewer-cpu 0`` the simulation's core (the conservative case: every cycle the viewer's
process uses is taken from the simulation). The affinities are read back each time and the report says whether
they all held. Then ``none`` is the simulation alone on CPU 0, and ``viewer`` pays what the viewer costs on the
simulation's thread (snapshots, writing them to the socket), what its process costs on the simulation's core (with
``--viewer-cpu 0``), plus whatever a busy neighbouring CPU costs (caches, memory bandwidth: ``idle`` shows it).
``--no-pin``: everything shares the machine's cores, as when the browser runs on the simulation's machine without a
GPU (software WebGL then takes about a core).

Conditions (the default four, and with ``--diagnostics`` three more that show where a cost comes from):

* ``none``:    no viewer serviced, every browser frozen: a run without a viewer;
* ``again``:   the same as ``none`` on a second simulation: ``again / none`` is the noise floor of the ratios (this
               machine's speed changes within a second by tens of percent);
* ``drawing``: (pinned only) no viewer serviced; browser F running, drawing the updates of viewer F, which a
               simulation in another process (the feeder, ``--feed``, at ``--feeder-factor`` x real time, default
               0.25) feeds at ``rate`` Hz; the feeder, its viewer's process and browser F on CPU 1, frozen outside
               this condition. It puts on CPU 1 what ``viewer`` puts there (a browser drawing 30 updates a second,
               a viewer's process), without this simulation's viewer: ``viewer / drawing`` is the viewer's own
               cost, as with the browser on the user's computer; ``drawing / none`` is what the browser's software
               rendering on the neighbouring CPU costs this simulation on this VM;
* ``viewer``:  viewer A serviced between steps (as ``sigcore run --viewer`` does: a snapshot at most ``rate``
               times a second, sent to its process, which pushes it to the browser), browser A running;
* ``idle``:    (diagnostics) no viewer serviced, browser A running (connected, showing its scene, no updates);
* ``niced``:   (diagnostics, ``--no-pin`` only) viewer B, browser B running at nice 19: the browser only gets what
               the simulation leaves of the cores;
* ``frozen``:  (diagnostics) viewer C, its connected browser C frozen: what the viewer costs (snapshots; its
               process serializing and sending to a client), without the browser's rendering. viser holds the
               updates for the frozen browser (and drops superseded ones);
* ``alone``:   (diagnostics) viewer D, which no browser ever opened: snapshots and the viewer's process, nothing
               sent.

Target (issue 13): steps per second with the viewer and one browser >= 0.9 x without a viewer, same run (pinned).
The report gives the ratios of the medians over the rounds and, less sensitive to the machine's drift, the median
of the per-round ratios with a 95 % confidence interval.

Latency of an update, from the moment the snapshot is taken on the simulation thread (``Snapshot.wall``,
``time.perf_counter``, the machine's monotonic clock, shared by its processes) to (a) the viewer's process having
handed it to viser (its report, ``push_observers``) and (b) the browser's
DOM showing its status line ("step N"): a MutationObserver in the page records ``performance.timeOrigin +
performance.now()`` when the number changes, and the time of the next animation frame after it. The browser's
epoch clock is mapped to ``perf_counter`` through ``time.time()`` (checked at start: a browser reading must fall
between two Python readings around it). Measured in the ``viewer`` rounds (as fast as possible), the niced rounds
(``--no-pin``), and a real-time phase afterwards (``--realtime`` seconds of viewer A at real-time factor 1, how a
person watches).
"""

from __future__ import annotations

import argparse
import os
import shutil
import signal
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from sigcore_viewer import WebViewer
from sigcore_viewer.snapshot import Pushed

from sigcore.sim import Simulation, run
from sigcore.transport import Transport
from sigcore.world import parse_world

ROOT = Path(__file__).resolve().parent.parent
TICK = os.sysconf("SC_CLK_TCK")
SIM_CPU, BROWSER_CPU = 0, 1  # with pinning: this process on CPU 0, the browsers on CPU 1
STATUS = "//p[contains(., 'real-time factor') and contains(., 'step ')]"

RECORD = """
const rec = window.__sigRec = [];
let last = null, el = null;
const find = () => document.evaluate("XPATH", document, null, XPathResult.FIRST_ORDERED_NODE_TYPE,
                                     null).singleNodeValue;
const look = () => {
  if (!el || !el.isConnected) el = find();
  if (!el) return;
  const m = /step (\\d+)/.exec(el.textContent);
  if (!m || m[1] === last) return;
  last = m[1];
  const r = [performance.timeOrigin + performance.now(), Number(m[1]), 0];
  rec.push(r);
  requestAnimationFrame(() => { r[2] = performance.timeOrigin + performance.now(); });
};
new MutationObserver(look).observe(document.body, {subtree: true, childList: true, characterData: true});
look();
window.__sigFrames = 0;
const tick = () => { window.__sigFrames++; requestAnimationFrame(tick); };
requestAnimationFrame(tick);
return rec.length;
""".replace("XPATH", STATUS)
FRAMES = "return window.__sigFrames;"

CONDITIONS = ("none", "again", "idle", "drawing", "viewer", "niced", "frozen", "alone")
LABELS = {"none": "no viewer (browsers frozen)", "again": "no viewer again (a second simulation)",
          "idle": "no viewer, browser A connected and idle",
          "drawing": "no viewer, browser F drawing another run",
          "viewer": "viewer A, browser A connected", "niced": "viewer B, browser B at nice 19",
          "frozen": "viewer C, browser C connected but frozen", "alone": "viewer D, no browser ever connected"}
BROWSER = {"idle": "A", "drawing": "F", "viewer": "A", "niced": "B"}  # the browser running (others: frozen)
VIEWER = {"viewer": "A", "niced": "B", "frozen": "C", "alone": "D"}  # the viewer serviced during a condition


class _Serviced(Transport):
    """Delegates ``service`` to a started viewer, leaves it started across runs, and adds up the time it took."""

    name = "bench-viewer"

    def __init__(self, viewer: WebViewer) -> None:
        self.viewer = viewer
        self.busy = 0.0

    def start(self, sim: Simulation) -> None:
        pass

    def service(self, timeout: float) -> None:
        t = time.perf_counter()
        self.viewer.service(timeout)
        self.busy += time.perf_counter() - t

    def stop(self) -> None:
        pass


def _p(values: list[float], q: float) -> float:
    s = sorted(values)
    return s[min(len(s) - 1, int(q * len(s)))]


def _median_ci(values: list[float]) -> tuple[float, float, float]:
    """The median of ``values`` and a distribution-free 95 % confidence interval for it (order statistics
    n/2 -+ 0.98 sqrt(n), the normal approximation of the binomial)."""
    s = sorted(values)
    n = len(s)
    half = 0.98 * n ** 0.5
    lo, hi = max(0, int(n / 2 - half)), min(n - 1, int(n / 2 + half + 0.999))
    return statistics.median(s), s[lo], s[hi]


def _children(pid: int) -> list[int]:
    """Every descendant process of ``pid``."""
    parents: dict[int, list[int]] = {}
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/stat") as f:
                stat = f.read()
        except OSError:
            continue
        parents.setdefault(int(stat[stat.rindex(")") + 2:].split()[1]), []).append(int(entry))
    out, todo = [], [pid]
    while todo:
        for child in parents.get(todo.pop(), []):
            out.append(child)
            todo.append(child)
    return out


def _pin(pids: Sequence[int | str], cpu: int) -> tuple[int, int, int]:
    """Every thread of these processes (``"self"``: this one) on CPU ``cpu`` only, read back after: (processes,
    threads, threads whose affinity is not ``{cpu}``). On Linux an affinity belongs to a thread, and a new thread or
    process inherits its creator's; processes or threads that ended meanwhile are skipped."""
    procs = threads = wrong = 0
    for pid in pids:
        try:
            tids = [int(t) for t in os.listdir(f"/proc/{pid}/task")]
        except OSError:
            continue
        procs += 1
        for tid in tids:
            try:
                os.sched_setaffinity(tid, {cpu})
                held = os.sched_getaffinity(tid) == {cpu}
            except ProcessLookupError:
                continue
            threads += 1
            wrong += not held
    return procs, threads, wrong


def _cpu_ticks() -> dict[int, tuple[int, int, int]]:
    """(busy, steal, all) clock ticks of each CPU so far, from /proc/stat (steal: taken by the host)."""
    out = {}
    with open("/proc/stat") as f:
        for line in f:
            name, *fields = line.split()
            if name[:3] == "cpu" and name[3:].isdigit():
                user, nice, system, idle, iowait, irq, softirq, steal = (int(x) for x in fields[:8])
                out[int(name[3:])] = (user + nice + system + irq + softirq, steal,
                                      user + nice + system + idle + iowait + irq + softirq + steal)
    return out


def _proc_cpu(pids: list[int]) -> dict[str, float]:
    """CPU time (user + system) of these Chromium processes so far [s] (10 ms resolution), by process type
    (``gpu-process``: SwiftShader's rendering, ``renderer``: the page, ``browser``, ``utility``, ...)."""
    out: dict[str, float] = {}
    for pid in pids:
        try:
            with open(f"/proc/{pid}/stat") as f:
                fields = f.read().rsplit(")", 1)[1].split()
            with open(f"/proc/{pid}/cmdline") as f:
                cmdline = f.read().replace("\x00", " ")
        except OSError:
            continue
        kind = next((a[7:] for a in cmdline.split() if a.startswith("--type=")), "browser")
        out[kind] = out.get(kind, 0.0) + (int(fields[11]) + int(fields[12])) / TICK
    return out


def _chromium(before: dict[str, float], after: dict[str, float], wall: float) -> str:
    """Chromium's CPU between two :func:`_proc_cpu` readings [% of one core], total and by process type."""
    used = {k: (after.get(k, 0.0) - before.get(k, 0.0)) / wall * 100 for k in after}
    parts = ", ".join(f"{k} {v:.0f}" for k, v in sorted(used.items(), key=lambda kv: -kv[1]) if v >= 1.0)
    return f"{sum(used.values()):6.1f}" + (f" ({parts})" if parts else "")


def _thread_cpu(viewers: dict[str, int]) -> dict[str, float]:
    """CPU time so far [s]: of this process's simulation (main) thread, of its other threads (``other``), and of
    each viewer's process (``viewer A``...: viser's server, its push thread, its reader; every thread)."""
    out = {"sim": 0.0, "other": 0.0}
    for t in threading.enumerate():
        try:
            cpu = time.clock_gettime(time.pthread_getcpuclockid(t.ident))  # type: ignore[arg-type]
        except (OSError, TypeError):
            continue
        out["sim" if t is threading.main_thread() else "other"] += cpu
    for v, pid in viewers.items():
        try:
            with open(f"/proc/{pid}/stat") as f:
                fields = f.read().rsplit(")", 1)[1].split()
            out[f"viewer {v}"] = (int(fields[11]) + int(fields[12])) / TICK
        except OSError:
            out[f"viewer {v}"] = 0.0
    return out


def _preempted() -> int:
    """How often the simulation (main) thread was preempted so far (its involuntary context switches)."""
    with open(f"/proc/self/task/{threading.main_thread().native_id}/status") as f:
        return next(int(line.split()[1]) for line in f if line.startswith("nonvoluntary_ctxt_switches"))


def _clock_offset() -> float:
    """``time.time() - time.perf_counter()``, from the closest of a few paired readings."""
    best = None
    for _ in range(20):
        a = time.perf_counter()
        w = time.time()
        b = time.perf_counter()
        if best is None or b - a < best[0]:
            best = (b - a, w - (a + b) / 2)
    assert best is not None
    return best[1]


class _Browser:
    """A headless Chromium on a viewer's page (its own profile directory, removed at the end)."""

    def __init__(self, url: str, chromedriver: str, cpu: int | None) -> None:
        self.url, self.chromedriver, self.cpu = url, chromedriver, cpu
        self.profile = tempfile.mkdtemp(prefix="sigcore-bench-chromium-")
        self.driver: Any = None
        self.driver_pid = 0
        self.pids: list[int] = []
        self.shown_after = float("nan")
        self.error: BaseException | None = None
        self.pinned = (0, 0, 0)  # what the last pin() found: (processes, threads, threads not on self.cpu)
        self.feeder: list[int] = []  # browser F: the feeder and its viewer's process, frozen and thawed with it

    def open(self) -> None:
        """Start the browser and wait until the page shows the viewer's status line (run on a thread)."""
        try:
            from selenium import webdriver
            from selenium.webdriver.chrome.service import Service
            from selenium.webdriver.common.by import By

            t0 = time.perf_counter()
            opts = webdriver.ChromeOptions()
            for arg in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                        "--disable-background-networking", "--disable-component-update", "--disable-sync",
                        "--no-first-run", "--window-size=1280,800", "--enable-unsafe-swiftshader",
                        f"--user-data-dir={self.profile}"):
                opts.add_argument(arg)
            self.driver = webdriver.Chrome(service=Service(self.chromedriver), options=opts)
            self.driver_pid = self.driver.service.process.pid
            self.pin()  # right after the driver started (Chromium with it): the page loads on the browsers' CPU
            self.driver.get(self.url)
            deadline = time.monotonic() + 120.0
            while not self.driver.find_elements(By.XPATH, STATUS):
                if time.monotonic() > deadline:
                    raise RuntimeError(f"{self.url} did not show the viewer's status line within 120 s")
                time.sleep(0.2)
            self.driver.execute_script(RECORD)
            self.shown_after = time.perf_counter() - t0
        except BaseException as e:  # reported by the main thread
            self.error = e

    def find_processes(self) -> None:
        self.pids = _children(self.driver_pid)

    def pin(self) -> None:
        """chromedriver and every process under it, every thread of each, on :attr:`cpu` (when pinning)."""
        if self.cpu is not None:
            self.pinned = _pin([self.driver_pid, *_children(self.driver_pid)], self.cpu)

    def signal(self, sig: int) -> None:
        for pid in self.pids + self.feeder:
            try:
                os.kill(pid, sig)
            except ProcessLookupError:
                pass

    def nice(self, value: int) -> None:
        """Every thread of every browser process at niceness ``value``."""
        for pid in self.pids:
            try:
                tids = os.listdir(f"/proc/{pid}/task")
            except OSError:
                continue
            for tid in tids:
                try:
                    os.setpriority(os.PRIO_PROCESS, int(tid), value)
                except OSError:
                    pass

    def script(self, code: str) -> Any:
        return self.driver.execute_script(code)

    def close(self) -> None:
        self.signal(signal.SIGCONT)
        if self.driver is not None:
            try:
                self.driver.quit()
            except Exception as e:  # leftovers are killed below
                print(f"quitting the browser: {type(e).__name__}: {e}")
        leftovers = set(self.pids) | (set(_children(self.driver_pid)) | {self.driver_pid} if self.driver_pid else set())
        for pid in leftovers:
            try:
                os.kill(pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
        shutil.rmtree(self.profile, ignore_errors=True)


def _latency(pushes: dict[int, tuple[float, float]], records: list[list[float]], offset: float,
             first: int, end: int) -> dict[str, list[float]]:
    """Latencies [ms] of the updates of steps ``first`` <= step < ``end``: handed to viser, shown in the DOM,
    next animation frame after."""
    out: dict[str, list[float]] = {"push": [], "dom": [], "frame": []}
    for step, (taken, sent) in pushes.items():
        if first <= step < end:
            out["push"].append((sent - taken) * 1e3)
    for t_dom, shown, t_frame in records:
        s = int(shown)
        if first <= s < end and s in pushes:
            taken = pushes[s][0]
            out["dom"].append((t_dom / 1e3 - offset - taken) * 1e3)
            if t_frame:
                out["frame"].append((t_frame / 1e3 - offset - taken) * 1e3)
    return out


def feed(world: str, controller: str, rate: float, factor: float) -> None:
    """The feeder of condition ``drawing`` (``--feed``): a simulation paced at ``factor`` x real time (no catching
    up after a SIGSTOP) with a viewer on the next free port; prints ``ready URL``, runs until stdin closes."""
    agent, _, name = controller.partition("=")
    sim = Simulation(parse_world(world), "mujoco", controllers={agent: name})
    viewer = WebViewer(rate=rate)
    viewer.open()
    viewer.start(sim)
    print(f"ready {viewer.url}", flush=True)
    done = threading.Event()

    def wait_for_stdin_to_close() -> None:
        sys.stdin.read()
        done.set()

    threading.Thread(target=wait_for_stdin_to_close, daemon=True).start()
    t0, w0 = sim.time, time.perf_counter()
    try:
        while not done.is_set():
            viewer.service(0.0)
            sim.step()
            ahead = (sim.time - t0) / factor - (time.perf_counter() - w0)
            if ahead > 0.001:
                time.sleep(ahead)
            elif ahead < -0.05:  # it was frozen: go on from here
                t0, w0 = sim.time, time.perf_counter()
    finally:
        viewer.stop()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("world", nargs="?", default=str(ROOT / "worlds" / "cleanup.xml"))
    ap.add_argument("--controller", default="robot_000=cleanup.robot", help="AGENT=CONTROLLER, so that it moves")
    ap.add_argument("--steps", type=int, default=600, help="steps per round and condition")
    ap.add_argument("--rounds", type=int, default=50,
                    help="rounds (the scripted robot finishes the task after about 45000 steps, which ends the run: "
                         "keep rounds x steps + 6000 below that)")
    ap.add_argument("--diagnostics", action="store_true",
                    help="also the conditions idle, frozen and alone (and niced with --no-pin): where a cost comes "
                         "from; each makes a round longer")
    ap.add_argument("--rate", type=float, default=30.0, help="viewer updates per wall second [Hz]")
    ap.add_argument("--realtime", type=float, default=10.0, help="seconds of the real-time latency phase")
    ap.add_argument("--no-pin", dest="pin", action="store_false",
                    help=f"no CPU pinning (default: this process on CPU {SIM_CPU}, the browsers on CPU {BROWSER_CPU})")
    ap.add_argument("--viewer-cpu", type=int, choices=(SIM_CPU, BROWSER_CPU), default=BROWSER_CPU,
                    help=f"with pinning, the CPU of the viewers' processes (default {BROWSER_CPU}: the machine's "
                         f"other core, beside the browsers; {SIM_CPU}: the simulation's core, the conservative case)")
    ap.add_argument("--feeder-factor", type=float, default=0.25,
                    help="real-time factor of the feeder's simulation (condition drawing; default 0.25: about 5 %% of "
                         "a CPU, so that CPU 1 carries what it carries in condition viewer)")
    ap.add_argument("--feed", action="store_true", help=argparse.SUPPRESS)  # this script as the feeder
    ap.add_argument("--chromedriver", default="/usr/bin/chromedriver")
    ap.add_argument("--smoke", action="store_true", help="1 round of 200 steps, 2 s at real time: a check that the "
                    "bench runs, not a measurement")
    args = ap.parse_args()
    if args.smoke:
        args.rounds, args.steps, args.realtime = 1, 200, 2.0
    if args.feed:
        feed(args.world, args.controller, args.rate, args.feeder_factor)
        return
    pin: bool = args.pin
    allowed = sorted(os.sched_getaffinity(0))
    checks: dict[str, list[tuple[int, int, int]]] = {"self": [], "chromium": [], "viewers": [], "feeder": []}
    feeder: subprocess.Popen[str] | None = None
    if pin:
        if not {SIM_CPU, BROWSER_CPU} <= set(allowed):
            raise SystemExit(f"pinning needs CPUs {SIM_CPU} and {BROWSER_CPU}; this process may run on {allowed} "
                             "(--no-pin to run unpinned)")
        os.sched_setaffinity(0, {SIM_CPU})  # this thread, before any viewer or browser: what it starts inherits it
        checks["self"].append(_pin(["self"], SIM_CPU))  # and any thread an import started
    load0 = os.getloadavg()

    wanted = set(CONDITIONS) if args.diagnostics else {"none", "again", "drawing", "viewer"}
    conditions = tuple(c for c in CONDITIONS if c in wanted and not (pin and c == "niced")
                       and not (not pin and c == "drawing"))
    owner = {VIEWER[c]: c for c in conditions if c in VIEWER}  # viewer letter -> its condition: A (B) C D
    agent, _, controller = args.controller.partition("=")
    world = parse_world(args.world)
    sims = {c: Simulation(world, "mujoco", controllers={agent: controller}) for c in conditions}
    viewers = {v: WebViewer(rate=args.rate) for v in owner}
    serviced = {v: _Serviced(viewer) for v, viewer in viewers.items()}
    pushes: dict[str, dict[int, tuple[float, float]]] = {v: {} for v in owner}  # step -> (taken, handed over)
    for v, viewer in viewers.items():
        def pushed(report: Pushed, into: dict[int, tuple[float, float]] = pushes[v]) -> None:
            into[report.step] = (report.taken, report.handed)
        viewer.push_observers.append(pushed)
    browsers: dict[str, _Browser] = {}
    started: list[WebViewer] = []
    t_start = time.perf_counter()

    viewer_pids: dict[str, int] = {}

    def pin_all() -> None:
        """Pin (again) and read back: this process's threads on CPU 0, every browser process on CPU 1, the viewers'
        processes on ``--viewer-cpu``."""
        checks["self"].append(_pin(["self"], SIM_CPU))
        checks["viewers"].append(_pin(list(viewer_pids.values()), args.viewer_cpu))
        if "F" in browsers:
            checks["feeder"].append(_pin(browsers["F"].feeder, BROWSER_CPU))
        for b in browsers.values():
            b.pin()
            checks["chromium"].append(b.pinned)

    try:
        for v, c in owner.items():
            viewers[v].open()
            viewers[v].start(sims[c])
            started.append(viewers[v])
            viewer_pids[v] = viewers[v].process_id or 0
            if v != "D":
                browsers[v] = _Browser(viewers[v].url, args.chromedriver, BROWSER_CPU if pin else None)
        if "drawing" in conditions:
            feeder = subprocess.Popen(
                [sys.executable, __file__, "--feed", "--rate", str(args.rate), "--feeder-factor",
                 str(args.feeder_factor), "--controller", args.controller, args.world],
                stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True,
                preexec_fn=lambda: os.sched_setaffinity(0, {BROWSER_CPU}))  # it and its viewer's process
            assert feeder.stdout is not None
            ready = feeder.stdout.readline().split()
            if not ready or ready[0] != "ready":
                raise SystemExit(f"the feeder did not start (it printed {ready!r})")
            browsers["F"] = _Browser(ready[1], args.chromedriver, BROWSER_CPU)
            browsers["F"].feeder = [feeder.pid, *_children(feeder.pid)]
        print(f"viewers at {', '.join(viewer.url for viewer in viewers.values())}; starting {len(browsers)} "
              f"headless Chromium ({', '.join(browsers)})", flush=True)
        if pin:
            checks["self"].append(_pin(["self"], SIM_CPU))  # to be sure
            checks["viewers"].append(_pin(list(viewer_pids.values()), args.viewer_cpu))
        openers = [threading.Thread(target=b.open, daemon=True) for b in browsers.values()]
        for t in openers:
            t.start()
        for t in openers:
            t.join()
        for v, b in browsers.items():
            if b.error is not None:
                raise SystemExit(f"browser {v}: {type(b.error).__name__}: {b.error}")
            b.find_processes()
        print("pages shown after " + ", ".join(f"{b.shown_after:.1f} s" for b in browsers.values()) +
              "; warming up", flush=True)
        if pin:
            started_pins = {v: b.pinned for v, b in browsers.items()}  # read back right after each driver started
            pin_all()
            own, theirs = checks["self"][-1], checks["chromium"][-len(browsers):]
            ok = own[2] == 0 and all(w == 0 for _, _, w in theirs) and all(w == 0 for _, _, w in
                                                                             started_pins.values())
            ok = ok and checks["viewers"][-1][2] == 0
            print(f"pinned: this process ({own[1]} threads) to CPU {SIM_CPU}; the viewers' processes "
                  f"({checks['viewers'][-1][1]} threads) to CPU {args.viewer_cpu}; chromedriver and Chromium to CPU "
                  f"{BROWSER_CPU} (" + "; ".join(f"{v}: {p} processes, {t} threads" for v, (p, t, _) in
                                                  zip(browsers, theirs, strict=True)) +
                  f"); read back: {'every thread on its CPU' if ok else 'NOT every thread on its CPU'}", flush=True)
        else:
            print(f"not pinned (--no-pin): everything shares CPUs {allowed}", flush=True)

        # the browser clock against Python's: a browser reading must fall between two time.time() readings
        offset = _clock_offset()
        brackets = []
        for _ in range(5):
            before = time.time()
            reading = browsers["A"].script("return performance.timeOrigin + performance.now();") / 1e3
            after = time.time()
            brackets.append((reading - before, after - reading))
        clock_ok = all(lo >= -0.0005 and hi >= -0.0005 for lo, hi in brackets)

        warm = 1000  # 2 s of simulated time; the viewers' at real time so that the pages render their updates
        for c, sim in sims.items():
            run(sim, steps=warm, realtime_factor=1.0 if c in VIEWER else None,
                transport=serviced[VIEWER[c]] if c in VIEWER else None)
        for v, b in browsers.items():
            if not b.script("return window.__sigRec.length;"):
                raise SystemExit(f"page {v} recorded no update of its status line while warming up")
        time.sleep(2.0)  # let the pages settle
        for b in browsers.values():
            b.find_processes()
        if "B" in browsers:
            browsers["B"].nice(19)

        rates: dict[str, list[float]] = {c: [] for c in conditions}
        cpu_sim: dict[str, list[float]] = {c: [] for c in conditions}  # simulation-thread CPU [us/step]
        use: dict[str, dict[str, float]] = {c: dict.fromkeys(("sim", "other", "viewer", "wall", "frames", "service",
                                                              "updates", "preempted"), 0.0) for c in conditions}
        chromium_cpu: dict[str, dict[str, float]] = {c: {} for c in conditions}  # CPU [s] by process type
        per_cpu: dict[str, dict[int, list[int]]] = {c: {} for c in conditions}  # CPU -> [busy, steal, all] ticks
        ranges: dict[str, list[tuple[int, int]]] = {c: [] for c in conditions}  # steps of the viewers' rounds
        print(f"{args.rounds} rounds x {args.steps} steps per condition, order rotated each round", flush=True)
        for r in range(args.rounds):
            for b in browsers.values():
                b.find_processes()  # Chromium may have started processes since
            if pin:
                pin_all()
            all_pids = [pid for b in browsers.values() for pid in b.pids]
            k = r % len(conditions)
            order = conditions[k:] + conditions[:k]
            line = []
            for c in order:
                sim = sims[c]
                running = BROWSER.get(c)
                for v, b in browsers.items():
                    if v != running:
                        b.signal(signal.SIGSTOP)
                time.sleep(0.05)
                frames0 = browsers[running].script(FRAMES) if running else 0
                transport = serviced[VIEWER[c]] if c in VIEWER else None
                viewer = viewers[VIEWER[c]] if c in VIEWER else None
                before_t, before_p, before_c = _thread_cpu(viewer_pids), _proc_cpu(all_pids), _cpu_ticks()
                busy0 = transport.busy if transport else 0.0
                pushed0, step0 = (viewer.pushed if viewer else 0), sim.worlds.elapsed_steps
                preempted0 = _preempted()
                c0 = time.thread_time()
                rep = run(sim, steps=args.steps, realtime_factor=None, transport=transport)
                cpu = time.thread_time() - c0
                use[c]["preempted"] += _preempted() - preempted0
                after_t, after_p, after_c = _thread_cpu(viewer_pids), _proc_cpu(all_pids), _cpu_ticks()
                if running:
                    use[c]["frames"] += browsers[running].script(FRAMES) - frames0
                for b in browsers.values():
                    b.signal(signal.SIGCONT)
                if rep.steps != args.steps:
                    raise SystemExit(f"round {r + 1} ({c}) ran {rep.steps} steps, not {args.steps} "
                                     f"(stopped by {rep.stopped_by}): fewer --steps or --rounds")
                rates[c].append(rep.steps / rep.wall_time)
                cpu_sim[c].append(cpu / rep.steps * 1e6)
                for key in ("sim", "other"):
                    use[c][key] += after_t[key] - before_t[key]
                use[c]["viewer"] += sum(after_t[k] - before_t[k] for k in after_t if k.startswith("viewer "))
                for kind in after_p:
                    chromium_cpu[c][kind] = chromium_cpu[c].get(kind, 0.0) + after_p[kind] - before_p.get(kind, 0.0)
                for n, ticks in after_c.items():
                    acc = per_cpu[c].setdefault(n, [0, 0, 0])
                    for i in range(3):
                        acc[i] += ticks[i] - before_c.get(n, (0, 0, 0))[i]
                use[c]["wall"] += rep.wall_time
                text = f"{c} {rates[c][-1]:5.0f}"
                if viewer is not None and transport is not None:
                    use[c]["service"] += transport.busy - busy0
                    use[c]["updates"] += viewer.pushed - pushed0
                    ranges[c].append((step0, sim.worlds.elapsed_steps))
                    text += f" ({viewer.pushed - pushed0} updates)"
                line.append(text)
                time.sleep(0.3)  # the viewers' processes finish, the browsers catch up: nothing spills over
            print(f"  round {r + 1} [steps/s]: " + ",  ".join(line), flush=True)

        print(f"real-time phase: {args.realtime:g} s of viewer A at real-time factor 1", flush=True)
        for b in browsers.values():
            b.find_processes()
        if pin:
            pin_all()
        all_pids = [pid for b in browsers.values() for pid in b.pids]
        sim = sims["viewer"]
        step0 = sim.worlds.elapsed_steps
        others = [b for v, b in browsers.items() if v != "A"]
        for b in others:
            b.signal(signal.SIGSTOP)
        frames0 = browsers["A"].script(FRAMES)
        before_t, before_p = _thread_cpu(viewer_pids), _proc_cpu(all_pids)
        rt = run(sim, duration=args.realtime, realtime_factor=1.0, transport=serviced["A"])
        after_t, after_p = _thread_cpu(viewer_pids), _proc_cpu(all_pids)
        rt_fps = (browsers["A"].script(FRAMES) - frames0) / rt.wall_time
        for b in others:
            b.signal(signal.SIGCONT)
        rt_use = {key: (after_t[key] - before_t[key]) / rt.wall_time for key in ("sim", "other", "viewer A")}
        rt_chromium = _chromium(before_p, after_p, rt.wall_time)
        time.sleep(1.0)  # the last updates reach the pages
        records = {v: b.script("return window.__sigRec;") for v, b in browsers.items()}
        load = os.getloadavg()
    finally:
        for b in browsers.values():
            b.close()
        for viewer in started:
            viewer.stop()
        if feeder is not None:
            feeder.communicate(timeout=30)  # stdin closed: it stops its viewer and ends

    # ------------------------------------------------------------------ report
    dt = world.timestep
    med = {c: statistics.median(v) for c, v in rates.items()}
    print()
    print(f"world: {args.world}  timestep {dt} s  controller {args.controller}  viewers at {args.rate:g} Hz  "
          f"{os.cpu_count()} CPUs  load average (1/5/15 min) {'/'.join(f'{x:.2f}' for x in load0)} before, "
          f"{'/'.join(f'{x:.2f}' for x in load)} at the end")
    print(f"browsers: headless Chromium 1280x800 (software WebGL: SwiftShader; no GPU), {', '.join(browsers)}, one per "
          "viewer, connected for the whole bench")
    if pin:
        mine, ch, vw = checks["self"], checks["chromium"], checks["viewers"]
        wrong = sum(w for _, _, w in mine) + sum(w for _, _, w in ch) + sum(w for _, _, w in vw)
        print(f"pinning: this process on CPU {SIM_CPU}, the viewers' processes ({min(t for _, t, _ in vw)}-"
              f"{max(t for _, t, _ in vw)} threads) on CPU {args.viewer_cpu}, "
              f"chromedriver and every Chromium process on CPU {BROWSER_CPU}, "
              f"set and read back {len(mine)} times (at start, after the browsers started, before every round and the "
              f"real-time phase): {min(t for _, t, _ in mine)}-{max(t for _, t, _ in mine)} threads of this process, "
              f"{min(p for p, _, _ in ch)}-{max(p for p, _, _ in ch)} processes / {min(t for _, t, _ in ch)}-"
              f"{max(t for _, t, _ in ch)} threads per browser; "
              + ("every thread was on its CPU" if wrong == 0 else f"{wrong} thread readings NOT on their CPU"))
    else:
        print(f"pinning: none (--no-pin): the simulation and the browsers share CPUs {allowed}")
    print(f"rounds: {args.rounds} x {args.steps} steps per condition (simulations in lockstep, order rotated each "
          "round); medians (range)")
    for c in conditions:
        print(f"  {LABELS[c]:41s} {med[c]:6.0f} steps/s ({min(rates[c]):.0f}-{max(rates[c]):.0f})  "
              f"{1e6 / med[c]:6.1f} us/step  sim-thread CPU {statistics.median(cpu_sim[c]):6.1f} us/step  "
              f"real-time factor {med[c] * dt:5.1f}")
    base = rates["none"]
    for c in conditions[1:]:
        target = {"viewer": "  (target >= 0.9; the browser's rendering on CPU 1 included)",
                  "again": "  (noise floor: same work)"}.get(c, "")
        print(f"ratio {c + ' / none:':16s} {med[c] / med['none']:.3f}{target}   per round: "
              f"{', '.join(f'{x / n:.2f}' for x, n in zip(rates[c], base, strict=True))}")
    if "drawing" in conditions:
        print(f"ratio viewer / drawing: {med['viewer'] / med['drawing']:.3f}  (target >= 0.9: the viewer's own cost, "
              "the same browser load on CPU 1 in both)   per round: "
              f"{', '.join(f'{x / n:.2f}' for x, n in zip(rates['viewer'], rates['drawing'], strict=True))}")
    print("median of the per-round ratios (95 % confidence interval of the median):")
    for c, ref in (("again", "none"), ("viewer", "none"), ("drawing", "none"), ("viewer", "drawing")):
        if c in conditions and ref in conditions:
            mid, lo, hi = _median_ci([x / n for x, n in zip(rates[c], rates[ref], strict=True)])
            print(f"  {c + ' / ' + ref + ':':18s} {mid:.3f} ({lo:.3f}-{hi:.3f})")
    print("CPU while each condition ran [% of one CPU]:")
    for c in conditions:
        u = use[c]
        w = u["wall"]
        text = (f"  {c:7s} simulation thread {u['sim'] / w * 100:5.1f} (preempted {u['preempted'] / w:3.0f}/s)   "
                f"its other threads {u['other'] / w * 100:4.1f}   viewers' processes {u['viewer'] / w * 100:5.1f}   "
                f"Chromium {_chromium({}, chromium_cpu[c], w)}")
        if c in BROWSER:
            text += f"   page {u['frames'] / w:.1f} frames/s"
        print(text)
        print("          per CPU (busy / stolen by the host): " + ",  ".join(
            f"CPU {n} {busy / total * 100:5.1f} / {steal / total * 100:4.1f}"
            for n, (busy, steal, total) in sorted(per_cpu[c].items()) if total))
    for c in VIEWER:
        u = use.get(c, {})
        if u.get("updates"):
            print(f"  {c:7s} {u['updates']:.0f} updates ({u['updates'] / u['wall']:.1f}/s); on the simulation "
                  f"thread viewer.service {u['service'] / u['updates'] * 1e3:.2f} ms per update (all its calls: "
                  f"{u['service'] / u['wall'] * 100:.1f} % of the wall time); the viewers' processes "
                  f"{u['viewer'] / u['updates'] * 1e3:.2f} ms CPU per update (10 ms ticks)")
    print(f"  real-time phase ({rt.steps} steps in {rt.wall_time:.1f} s): simulation thread {rt_use['sim'] * 100:.1f}"
          f"   its other threads {rt_use['other'] * 100:.1f}   viewer A's process {rt_use['viewer A'] * 100:.1f}   "
          "Chromium "
          f"{rt_chromium.strip()}   page {rt_fps:.1f} frames/s")
    lo = min(b[0] for b in brackets) * 1e3
    hi = min(b[1] for b in brackets) * 1e3
    clock = (f"browser clock - Python's within -{hi:.1f} .. +{lo:.1f} ms" if clock_ok else
             f"browser clock OUTSIDE Python's bracket: {lo:.1f} / {hi:.1f} ms; the page latencies are off")
    print(f"latency [ms] from the snapshot taken on the simulation thread ({clock}):")
    names = {"push": "handed to viser (viewer's process)", "dom": "shown in the page's DOM",
             "frame": "next animation frame after"}
    phases = [(f"{LABELS[c]}, as fast as possible", VIEWER[c], ranges[c]) for c in ("viewer", "niced", "frozen",
                                                                                     "alone") if c in conditions]
    phases.append(("viewer A, real time", "A", [(step0, sims["viewer"].worlds.elapsed_steps)]))
    for label, v, spans in phases:
        lat: dict[str, list[float]] = {"push": [], "dom": [], "frame": []}
        for first, end in spans:
            for key, values in _latency(pushes[v], records.get(v, []), offset, first, end).items():
                lat[key] += values
        if v in "CD":
            lat["dom"], lat["frame"] = [], []  # C's page shows them after it was thawed: not a latency
        print(f"  {label} ({len(lat['push'])} updates pushed, {len(lat['dom'])} seen in the page):")
        for key in ("push", "dom", "frame"):
            values = lat[key]
            if values:
                print(f"    {names[key]:32s} median {statistics.median(values):7.1f}  p90 {_p(values, 0.9):7.1f}  "
                      f"p99 {_p(values, 0.99):7.1f}  max {max(values):7.1f}")
    print(f"(total {time.perf_counter() - t_start:.0f} s)")

if __name__ == "__main__":
    main()
