"""``sigcore eval``: a solution (or an in-process controller) over many seeded episodes, on this machine or on a Ray
cluster; the command line part (options, progress, the final table). The work is in :mod:`sigcore.eval`."""

from __future__ import annotations

import os
import sys
from pathlib import Path
from typing import Annotated

import typer
from rich.progress import BarColumn, MofNCompleteColumn, Progress, ProgressColumn, Task, TextColumn
from rich.text import Text

from ..eval import (
    DOMAINS,
    ENV,
    EpisodeRow,
    Eta,
    EvalError,
    Settings,
    count,
    parse_domains,
    prepare,
    run_local,
    run_ray,
    summarize,
    write_summary,
)
from ..eval.domains import describe
from ..eval.results import EpisodeLog
from .common import err, fail, out

KINDS = {"timeout": "timed out", "not_started": "not started", "solution_crashed": "solution crashed",
         "simulator_error": "simulator error"}

EXIT_BELOW = 1
"""The exit code when the success rate is below ``--min-success``."""


def eval_command(
    world_file: Annotated[Path, typer.Argument(exists=True, dir_okay=False, help="world file (with <randomize>)")],
    solution: Annotated[str | None, typer.Option(
        help="the solution: a shell command started beside the simulator in each episode (its own ROS 2 domain, "
        "discovery on this machine only), e.g. 'python my_robot.py' or 'ros2 launch my_pkg task.launch.py'")] = None,
    controller: Annotated[list[str] | None, typer.Option(
        help="AGENT=CONTROLLER: an in-process controller instead of (or beside) a solution; without --solution the "
        "episodes run without ROS 2, as fast as possible")] = None,
    episodes: Annotated[int, typer.Option(min=1, help="how many episodes")] = 10,
    seed: Annotated[int, typer.Option(min=0, help="episode i's world is drawn with seed SEED + i")] = 0,
    workers: Annotated[int, typer.Option(min=1, help="episodes at once on this machine")] = 1,
    timeout: Annotated[float, typer.Option(min=1.0, help="wall-time limit of an episode [s]; it is then killed")]
    = 600.0,
    out_dir: Annotated[Path, typer.Option("--out", help="where episodes.csv, summary.json and each episode's "
                                          "logs go")] = Path("results"),
    resume: Annotated[bool, typer.Option("--resume", help="go on with the evaluation in --out: skip the episodes "
                                         "it holds")] = False,
    backend: Annotated[str, typer.Option(help="physics backend")] = "mujoco",
    duration: Annotated[float, typer.Option(min=0.001, help="at most this much simulated time per episode [s] (the "
                                            "task's end, e.g. the referee's time limit, usually comes first)")]
    = 3600.0,
    factor: Annotated[float | None, typer.Option(min=0.01, help="simulation pace, times real time (default with "
                                                 "--solution: 1, real time)")] = None,
    fast: Annotated[bool, typer.Option("--fast", help="as fast as possible (default without --solution)")] = False,
    wait_for: Annotated[list[str] | None, typer.Option(
        "--wait-for", help="TOPIC: the simulator holds at t = 0 until the solution has this topic's peers "
        "(sigcore run --wait-for)")] = None,
    cwd: Annotated[Path | None, typer.Option(file_okay=False, help="the solution's working folder (default: "
                                             "here)")] = None,
    ray_address: Annotated[str | None, typer.Option(
        "--ray", metavar="ADDRESS", help="run the episodes as Ray tasks on the cluster at ADDRESS (HOST:PORT of "
        "its head, or auto) instead of --workers")] = None,
    ray_cpus: Annotated[float, typer.Option(min=0.1, help="CPUs each episode declares on Ray")] = 1.0,
    ray_node_ip: Annotated[str | None, typer.Option(
        help="the address this driver gives Ray (default: 127.0.0.1 when --ray is on 127.0.0.1 or localhost)")]
    = None,
    ray_working_dir: Annotated[Path | None, typer.Option(
        file_okay=False, help="ship this folder to the workers as the tasks' working folder (the solution and "
        "the world in it, named relative to it)")] = None,
    domains: Annotated[str | None, typer.Option(
        "--domains", metavar="LOW-HIGH", help=f"the ROS_DOMAIN_IDs the episodes take theirs from, both included, "
        f"within 0-232 (default: ${ENV}, else {describe(DOMAINS)}); each running episode holds one no other holds")]
    = None,
    min_success: Annotated[float | None, typer.Option(
        "--min-success", metavar="RATE", help="exit 1 if the success rate is below RATE, a fraction from 0 to 1 "
        "(e.g. 0.8): the exit code gates CI")] = None,
) -> None:
    """Evaluate a solution over many seeded episodes: each episode draws the world with its seed, runs the
    simulator (ROS 2) and the solution in a ROS 2 domain of their own, waits for the task's end or the timeout and
    records score, result, events, times, exit codes and both logs. Prints a progress line per episode and a
    table at the end: success rate (95 % interval), mean score, failures by kind. Exits 0 when every episode ran
    (and the success rate is at least --min-success), 1 below --min-success, 2 for refused settings, 130 when
    interrupted."""
    if solution is None and not controller:
        raise fail(["sigcore eval needs --solution 'COMMAND' (a ROS 2 solution) or --controller AGENT=CONTROLLER "
                    "(e.g. robot_000=cleanup.robot)"])
    if fast and factor is not None:
        raise fail(["--fast and --factor exclude each other"])
    if ray_address is not None and workers != 1:
        raise fail(["--workers is for this machine; with --ray the cluster's CPUs decide (--ray-cpus per episode)"])
    if wait_for and solution is None:
        raise fail(["--wait-for needs --solution (the simulator waits for the solution's topics)"])
    if min_success is not None and not 0.0 <= min_success <= 1.0:
        raise fail([f"--min-success {min_success:g}: a success rate is a fraction; valid: 0 to 1 (e.g. 0.8 for "
                    "80 %)"])
    domain_range = _domains(domains)
    pace = ("--fast",) if fast or (solution is None and factor is None) else ("--factor", f"{factor or 1.0:g}")
    _check_world(world_file, seed)
    base = ray_working_dir.resolve() if ray_working_dir else None
    world = _relative(world_file.resolve(), base)
    settings = Settings(world, episodes, seed, solution, tuple(controller or ()), backend, timeout, pace,
                        tuple(wait_for or ()), _relative((cwd or Path.cwd()).resolve(), base) or ".", duration,
                        (domain_range.start, domain_range.stop - 1))
    out_dir = out_dir.resolve()
    try:
        rows = prepare(out_dir, settings, resume)
    except EvalError as e:
        raise fail([str(e)]) from None
    done = {r.episode for r in rows}
    todo = [settings.spec(i, out_dir, None if ray_address else sys.executable) for i in range(episodes)
            if i not in done]
    where = f"Ray cluster {ray_address}" if ray_address else f"{count(workers, 'worker')} here"
    ros = f", ROS 2 domains {describe(domain_range)}" if solution is not None else ""
    err.print(f"sigcore eval: {len(todo)} of {count(episodes, 'episode')} to run ({len(done)} recorded) on {where}"
              f"{ros}; results and logs in {out_dir}")
    if solution is not None and not ray_address and len(domain_range) < min(workers, len(todo)):
        err.print(f"warning: --domains {describe(domain_range)} holds {count(len(domain_range), 'domain')} for "
                  f"{count(workers, 'worker')}: at most {len(domain_range)} episode(s) run at once")
    log = EpisodeLog(out_dir)
    progress = _Progress(rows, episodes, Eta(len(todo), 1 if ray_address else workers))

    def record(row: EpisodeRow) -> None:
        log.append(row)
        progress.add(row)

    extra: dict[str, object] = {}
    interrupted = False
    with progress:
        try:
            if ray_address:
                node_ip = ray_node_ip or (_loopback(ray_address) and "127.0.0.1") or None

                def nodes(found: list[dict[str, object]]) -> None:
                    cpus = sum(float(str(n["cpus"] or 0)) for n in found if n["alive"])
                    progress.eta.set_workers(int(cpus // ray_cpus))
                    err.print(f"Ray cluster: {len(found)} node(s): " + ", ".join(
                        f"{n['address']} ({n['cpus']} CPUs{'' if n['alive'] else ', dead'})" for n in found))
                    outside = [str(n["address"]) for n in found if n["address"] != "127.0.0.1"]
                    if node_ip == "127.0.0.1" and outside:
                        err.print(f"warning: nodes on {', '.join(outside)}, not only 127.0.0.1: start the cluster "
                                  "with RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER=0 (docs/eval.md)")

                extra = run_ray(todo, ray_address, ray_cpus, record, node_ip=node_ip,
                                working_dir=str(base) if base else None, on_nodes=nodes)
            else:
                run_local(todo, workers, record)
        except EvalError as e:
            raise fail([str(e)]) from None
        except KeyboardInterrupt:
            interrupted = True
    summary = summarize(progress.rows, episodes)
    path = write_summary(out_dir, {**summary, **extra}, settings.as_dict())
    _table(summary, path, out_dir)
    if interrupted:
        raise fail([f"interrupted: {len(progress.rows)} of {count(episodes, 'episode')} recorded in "
                    f"{out_dir / 'episodes.csv'}; sigcore eval ... --out {out_dir} --resume goes on"], 130)
    wins, n = sum(r.success for r in progress.rows), len(progress.rows)
    rate = wins / n if n else None
    if min_success is not None:
        if rate is None or rate < min_success:
            shown = "none recorded" if rate is None else f"{100 * rate:.1f} %"
            raise fail([f"success rate {shown}, below --min-success {min_success:g} ({100 * min_success:g} %): "
                        f"exit {EXIT_BELOW}"], EXIT_BELOW)
        err.print(f"success rate {100 * rate:.1f} %, at least --min-success {min_success:g}: exit 0")


def _domains(option: str | None) -> range:
    """The domain range of ``--domains``, else of the environment variable, else the default; exit 2 on a bad one."""
    text, source = (option, "--domains") if option is not None else (os.environ.get(ENV), ENV)
    if text is None or (source == ENV and not text.strip()):
        return DOMAINS
    try:
        return parse_domains(text)
    except EvalError as e:
        raise fail([f"{source} {e}"]) from None


def _check_world(world_file: Path, seed: int) -> None:
    """Exit 2 now if the world cannot be read or drawn (rather than in every episode)."""
    from ..world import WorldError, parse_world
    from ..world.randomize import draw

    try:
        draw(parse_world(world_file), seed)
    except WorldError as e:
        raise fail([str(i) for i in e.issues]) from None


def _relative(path: Path, base: Path | None) -> str:
    if base is None:
        return str(path)
    try:
        return str(path.relative_to(base))
    except ValueError:
        raise fail([f"{path} is not in --ray-working-dir {base}: the workers would not have it"]) from None


def _loopback(address: str) -> bool:
    host = address.rsplit(":", 1)[0]
    return host in ("127.0.0.1", "localhost")


class _EtaColumn(ProgressColumn):
    """The bar's ETA, from :class:`Eta` (it knows the workers), recomputed at each refresh."""

    def __init__(self, eta: Eta) -> None:
        super().__init__()
        self.eta = eta

    def render(self, task: Task) -> Text:
        return Text(f"ETA {_seconds(self.eta.left())}")


def _seconds(left: float | None) -> str:
    return "-" if left is None else f"{left:.0f} s"


class _Progress:
    """Episodes done, the success rate so far and an ETA: a bar on a terminal, else a line per episode; an episode
    that did not end ``done`` gets a line naming its logs either way."""

    def __init__(self, rows: list[EpisodeRow], planned: int, eta: Eta) -> None:
        self.rows = list(rows)
        self.planned = planned
        self.eta = eta
        self.bar: Progress | None = None
        if err.is_terminal:
            self.bar = Progress(TextColumn("episodes"), BarColumn(), MofNCompleteColumn(),
                                TextColumn("{task.fields[rate]}"), _EtaColumn(eta), console=err)
            self.task = self.bar.add_task("eval", total=planned, completed=len(rows), rate=self._rate())

    def __enter__(self) -> _Progress:
        if self.bar is not None:
            self.bar.start()
        return self

    def __exit__(self, *exc: object) -> None:
        if self.bar is not None:
            self.bar.stop()

    def _rate(self) -> str:
        n, wins = len(self.rows), sum(r.success for r in self.rows)
        return f"success {wins}/{n} ({100 * wins / n:.0f} %)" if n else "success -"

    def add(self, row: EpisodeRow) -> None:
        self.rows.append(row)
        self.eta.ended(row.wall_time)
        what = f"{row.result or '-'}, score {row.score:g}" if row.score is not None else row.result or "-"
        line = f"episode {row.episode} (seed {row.seed}): {row.status}, {what}, {row.wall_time:.1f} s"
        trouble = f"; {row.reason}; logs: {row.folder}" if row.status != "done" else ""
        if self.bar is not None:
            self.bar.update(self.task, advance=1, rate=self._rate())
            if trouble:
                self.bar.console.print(line + trouble, soft_wrap=True)
            return
        err.print(f"{line}; {len(self.rows)}/{self.planned} done, {self._rate()}, ETA {_seconds(self.eta.left())}"
                  + trouble, soft_wrap=True)


def _table(summary: dict, path: Path, folder: Path) -> None:
    n = summary["episodes"]
    if not n:
        out.print("no episodes recorded")
        return
    success = summary["success_interval_95"]
    out.print(f"episodes:     {n} of {summary['planned']}")
    out.print(f"success rate: {100 * summary['success_rate']:.1f} %  (95 % interval {100 * success['low']:.1f}-"
              f"{100 * success['high']:.1f} %, {summary['succeeded']} of {n})")
    if summary["score_mean"] is not None:
        interval = summary["score_interval_95"]
        out.print(f"mean score:   {summary['score_mean']:.1f}  (95 % interval {interval['low']:.1f}-"
                  f"{interval['high']:.1f}, {count(summary['scored_episodes'], 'episode')} with a score)")
        out.print(f"score:        median {summary['score_median']:g}, min {summary['score_min']:g}, max "
                  f"{summary['score_max']:g}")
    excluded = summary["score_excluded"]
    if excluded["never_ran"]:
        out.print(f"not in score: {count(excluded['never_ran'], 'episode')} that never left t = 0 (not started, or "
                  "the solution crashed before)")
    if summary["sim_time_mean"] is not None:
        out.print(f"mean time:    {summary['sim_time_mean']:.1f} s simulated, {summary['wall_time_mean']:.1f} s wall")
    results = ", ".join(f"{k} {v}" for k, v in summary["results"].items())
    if results:
        out.print(f"results:      {results}")
    failures = ", ".join(f"{KINDS[k]} {v}" for k, v in summary["failures"].items())
    out.print(f"failures:     {failures}")
    out.print(f"logs:         {folder / 'episodes'}/NNNN/ (sim.log, solution.log, result.json); rows in "
              f"{folder / 'episodes.csv'}")
    out.print(f"summary:      {path}")
