"""Batch bakes on a Ray cluster: each scene one Ray task.

    python -m organtex.batch SCENES... -o DIR [--address ADDR | --local N]
                             [--cpus-per-task C] [--retries R] [--force]
                             [--atlas SIZE] [--manifest LIST]
                             [--vary N [--vary-seed S]]

Each scene bakes into DIR/NAME/ (NAME: its file name without .toml), as
``organtex bake`` writes it (scene.glb, report.json, preview.png,
interior/, unwraps/), atomically: a folder holds a whole bake or its
previous one, never half of one. A scene baked again starts from copies
of the interiors and unwraps its previous bake kept, so after a tissue
change only the textures are made again, as with ``organtex bake`` into
the same folder. Results stream in as tasks finish, with a progress bar.
A scene that fails is reported with its error while the others go on; a
task whose worker process dies (killed, out of memory, node lost) is
retried up to --retries times by Ray. A scene whose DIR/NAME/report.json
is newer than the scene file and everything it names is skipped unless
--force. DIR/summary.json lists every scene's status, error, seconds and
figures.

--vary N writes N variants of each scene into DIR/variants/ (myoma sizes
and positions and the cavity's size drawn at random, seeded by
--vary-seed) and bakes those instead.

Ray is the scheduler: --local N starts a Ray instance on this machine with
N CPUs, --address joins a running cluster (``ray start --head`` on one
node, ``ray start --address HEAD:6379`` on the others). Without Ray,
``organtex bake --manifest LIST --index N`` bakes the same scenes from job
arrays (README: a Slurm script).
"""

from __future__ import annotations

import argparse
import json
import os
import random
import re
import shutil
import socket
import sys
import time
from pathlib import Path

from . import OrgantexError, bake, check_scene


def output_name(scene: Path) -> str:
    """The folder a scene bakes into (as ``organtex bake --manifest``)."""
    return Path(scene).stem or "scene"


def _inputs(scene: Path) -> list:
    """The scene file and the files it names (meshes, includes,
    photographs), for the up-to-date check. Before Python 3.11 (no
    tomllib) only the scene file itself."""
    paths = [scene]
    try:
        import tomllib
    except ImportError:
        return paths
    try:
        data = tomllib.loads(scene.read_text())
    except (OSError, ValueError):
        return paths

    def walk(x):
        if isinstance(x, dict):
            for k, v in x.items():
                if k in ("file", "include", "photographs", "sections") and isinstance(v, (str, list)):
                    for p in [v] if isinstance(v, str) else v:
                        if isinstance(p, str):
                            paths.append(scene.parent / p)
                else:
                    walk(v)
        elif isinstance(x, list):
            for v in x:
                walk(v)

    walk(data)
    return paths


def up_to_date(scene: Path, out: Path) -> bool:
    """Whether ``out`` holds a bake newer than the scene and its inputs."""
    report = out / "report.json"
    if not report.exists():
        return False
    done = report.stat().st_mtime
    return all(not p.exists() or p.stat().st_mtime <= done for p in _inputs(scene))


def bake_one(scene: str, out_root: str, atlas, force: bool) -> dict:
    """Bake one scene into out_root/NAME (run as a Ray task)."""
    scene_path = Path(scene)
    name = output_name(scene_path)
    out = Path(out_root) / name
    result = {"scene": str(scene_path), "name": name, "host": socket.gethostname(),
              "node": _node_id()}
    if not force and up_to_date(scene_path, out):
        return {**result, "status": "skipped", "seconds": 0.0}
    out.parent.mkdir(parents=True, exist_ok=True)
    # Which process bakes it, for whoever watches the batch (and the
    # test that kills a worker mid-bake).
    running = Path(out_root) / f".{name}.running"
    running.write_text(f"{socket.gethostname()} {os.getpid()}\n")
    # The bake goes to a staging folder that replaces DIR/NAME whole once
    # it succeeds: a worker killed mid-bake leaves the previous bake (or
    # none) and a staging folder the retry clears.
    staging = Path(out_root) / f".{name}.staging"
    shutil.rmtree(staging, ignore_errors=True)
    _seed(out, staging)
    start = time.monotonic()
    try:
        report = bake(scene_path, staging, atlas=atlas)
        _replace(staging, out)
    except OrgantexError as e:
        # The scene is wrong, not the worker: no retry would help.
        shutil.rmtree(staging, ignore_errors=True)
        return {**result, "status": "failed", "error": str(e),
                "seconds": time.monotonic() - start}
    finally:
        running.unlink(missing_ok=True)
    return {**result, "status": "ok", "seconds": time.monotonic() - start,
            "figures": figures(report)}


def _seed(out: Path, staging: Path) -> None:
    """Give the staging folder copies of the previous bake's kept interiors
    and unwraps, so a bake after a tissue change takes them as ``organtex
    bake`` into the same folder does (each carries the digest of what it
    was made from; the bake checks it). Copies, not hard links: a morph's
    sections are copied over in place, which would write through a link
    into the previous bake."""
    for kept in ("interior", "unwraps"):
        if (out / kept).is_dir():
            shutil.copytree(out / kept, staging / kept)


def _replace(staging: Path, out: Path) -> None:
    """Put the folder ``staging`` in the place of ``out`` (two renames; the
    old bake is removed after)."""
    if out.exists():
        old = out.parent / f".{out.name}.old"
        shutil.rmtree(old, ignore_errors=True)
        os.replace(out, old)
        os.replace(staging, out)
        shutil.rmtree(old, ignore_errors=True)
    else:
        os.replace(staging, out)


def _node_id():
    """The Ray node running this task (None outside Ray)."""
    try:
        import ray
        # Asked outside Ray, the runtime context would start Ray, or join a
        # cluster it finds running on this machine.
        if not ray.is_initialized():
            return None
        return ray.get_runtime_context().get_node_id()
    except Exception:
        return None


def figures(report: dict) -> dict:
    """The figures of a bake report worth a summary line."""
    facets = report.get("facets", [])
    return {
        "facets": len(facets),
        "charts": sum(f.get("charts", 0) for f in facets),
        "bake_seconds": report.get("timings", {}).get("total_s"),
    }


# --- scene variants -------------------------------------------------------

_HEADER = re.compile(r"^\s*\[\[?([^\]]+)\]\]?\s*(#.*)?$")
_NUMBER = r"-?\d+(?:\.\d*)?(?:[eE][-+]?\d+)?"


def _resolve_paths(line: str, base: Path) -> str:
    """A ``key = "relative/path"`` line of a path key made absolute, so a
    variant written elsewhere still finds the base scene's files."""
    m = re.match(r'^(\s*(?:file|database|include|photographs|sections)\s*=\s*)(.*)$', line)
    if not m:
        # Inline tables: mesh = { file = "..." }
        return re.sub(r'(\bfile\s*=\s*")([^"]+)(")',
                      lambda g: g.group(1) + _absolute(g.group(2), base) + g.group(3), line)
    return m.group(1) + re.sub(r'"([^"]+)"', lambda g: '"' + _absolute(g.group(1), base) + '"',
                               m.group(2))


def _absolute(p: str, base: Path) -> str:
    return p if Path(p).is_absolute() else str((base / p).resolve())


def vary(scene: Path, count: int, seed: int, out_dir: Path) -> list:
    """``count`` variants of a scene, written to ``out_dir``: each myoma's
    radius and height scaled by 0.85-1.15 and its position moved by up to
    0.08 (of the cavity's parameter range), the cavity's length, width and
    depth scaled by 0.92-1.08 and its seed changed; relative paths made
    absolute. A draw the scene check refuses (myomas overlapping, one
    larger than the cavity) is drawn again, up to 50 times. Seeded: the
    same seed writes the same files."""
    text = scene.read_text()
    out_dir.mkdir(parents=True, exist_ok=True)
    written = []
    for k in range(count):
        rng = random.Random(f"{seed}:{scene.name}:{k}")
        path = out_dir / f"{output_name(scene)}-{k:03d}.toml"
        tmp = path.with_suffix(".toml.tmp")
        for attempt in range(50):
            tmp.write_text(_variant(text, scene.parent, rng, k) + "\n")
            try:
                check_scene(tmp)
                break
            except OrgantexError as e:
                error = e
        else:
            tmp.unlink()
            raise OrgantexError(f"{scene}: no valid variant {k} in 50 draws; the last: {error}")
        os.replace(tmp, path)
        written.append(path)
    return written


def _variant(text: str, base: Path, rng: random.Random, k: int) -> str:
    """One random variant of a scene's text (see `vary`)."""
    table = ""
    lines = []
    for line in text.splitlines():
        h = _HEADER.match(line)
        if h:
            table = h.group(1).strip()
        elif table.endswith("uterine_cavity.myoma"):
            line = re.sub(rf"^(\s*(?:radius|height)\s*=\s*)({_NUMBER})",
                          lambda g: f"{g.group(1)}{float(g.group(2)) * rng.uniform(0.85, 1.15):.4f}", line)
            line = re.sub(rf"^(\s*at\s*=\s*\[\s*)({_NUMBER})(\s*,\s*)({_NUMBER})",
                          lambda g: (f"{g.group(1)}{min(max(float(g.group(2)) + rng.uniform(-0.08, 0.08), 0.05), 0.95):.4f}"
                                     f"{g.group(3)}{min(max(float(g.group(4)) + rng.uniform(-0.08, 0.08), 0.05), 0.95):.4f}"),
                          line)
        elif table.endswith("uterine_cavity"):
            line = re.sub(rf"^(\s*(?:length|width|depth)\s*=\s*)({_NUMBER})",
                          lambda g: f"{g.group(1)}{float(g.group(2)) * rng.uniform(0.92, 1.08):.4f}", line)
            line = re.sub(r"^(\s*seed\s*=\s*)(\d+)", lambda g: f"{g.group(1)}{int(g.group(2)) + 1 + k}", line)
        lines.append(_resolve_paths(line, base))
    return "\n".join(lines)


# --- the batch ------------------------------------------------------------

def run(scenes, out: Path, address=None, local=None, cpus_per_task=1.0, retries=2,
        force=False, atlas=None, progress=True) -> dict:
    """Bake ``scenes`` as Ray tasks; the summary (also DIR/summary.json)."""
    import ray

    out.mkdir(parents=True, exist_ok=True)
    started = time.monotonic()
    if address:
        ray.init(address=address, logging_level="ERROR", log_to_driver=False)
    else:
        ray.init(num_cpus=local or os.cpu_count(), logging_level="ERROR", log_to_driver=False,
                 include_dashboard=False)
    ray_start = time.monotonic() - started
    try:
        # By reference to the importable module, not __main__ (which Ray
        # would pickle by value when run as python -m organtex.batch).
        from organtex import batch as importable
        task = ray.remote(num_cpus=cpus_per_task, max_retries=retries)(importable.bake_one)
        pending = {task.remote(str(s), str(out), atlas, force): str(s) for s in scenes}
        results = []
        bar = None
        if progress:
            try:
                from tqdm import tqdm
                bar = tqdm(total=len(pending), unit="scene", file=sys.stderr)
            except ImportError:
                bar = None
        while pending:
            done, _ = ray.wait(list(pending), num_returns=1)
            for ref in done:
                scene = pending.pop(ref)
                try:
                    r = ray.get(ref)
                except Exception as e:  # the worker died more often than retried
                    r = {"scene": scene, "name": output_name(Path(scene)), "status": "failed",
                         "error": f"{type(e).__name__}: {e}"}
                results.append(r)
                line = f"{r['status']:>7}  {r['name']}"
                if r["status"] == "failed":
                    line += f": {r['error']}"
                elif r["status"] == "ok":
                    line += f" ({r['seconds']:.1f} s)"
                if bar is not None:
                    bar.write(line)
                    bar.update(1)
                elif progress:
                    print(line, file=sys.stderr, flush=True)
        if bar is not None:
            bar.close()
    finally:
        ray.shutdown()
    results.sort(key=lambda r: r["name"])
    summary = {
        "scenes": len(results),
        "ok": sum(r["status"] == "ok" for r in results),
        "skipped": sum(r["status"] == "skipped" for r in results),
        "failed": sum(r["status"] == "failed" for r in results),
        "ray_start_seconds": ray_start,
        "seconds": time.monotonic() - started,
        "results": results,
    }
    tmp = out / "summary.json.tmp"
    tmp.write_text(json.dumps(summary, indent=2) + "\n")
    os.replace(tmp, out / "summary.json")
    return summary


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m organtex.batch",
                                     description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter,
                                     epilog=__doc__.split("\n\n", 2)[2])
    parser.add_argument("scenes", nargs="*", type=Path, help="scene files (.toml)")
    parser.add_argument("-o", "--output", type=Path, required=True, help="folder of the bakes")
    where = parser.add_mutually_exclusive_group()
    where.add_argument("--address", help="a running Ray cluster's address (HEAD:6379, or auto)")
    where.add_argument("--local", type=int, metavar="N", help="start Ray here with N CPUs (default: all)")
    parser.add_argument("--cpus-per-task", type=float, default=1.0, metavar="C",
                        help="CPUs Ray reserves for each bake (default 1)")
    parser.add_argument("--retries", type=int, default=2,
                        help="times a task whose worker died is retried (default 2)")
    parser.add_argument("--force", action="store_true", help="bake scenes that are up to date too")
    parser.add_argument("--atlas", type=int, metavar="SIZE", help="bake atlases (as organtex bake --atlas)")
    parser.add_argument("--manifest", type=Path, help="also the scenes this list names (one per line)")
    parser.add_argument("--vary", type=int, metavar="N", help="bake N seeded variants of each scene instead")
    parser.add_argument("--vary-seed", type=int, default=0, metavar="S", help="seed of the variants")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")
    args = parser.parse_args(argv)
    scenes = list(args.scenes)
    if args.manifest:
        from . import manifest
        try:
            scenes += [Path(p) for p in manifest(args.manifest)]
        except OrgantexError as e:
            parser.error(str(e))
    if not scenes:
        parser.error("give scene files or --manifest")
    missing = [s for s in scenes if not s.is_file()]
    if missing:
        parser.error(f"{missing[0]}: no such scene file")
    names = [output_name(s) for s in scenes]
    dup = {n for n in names if names.count(n) > 1}
    if dup and not args.vary:
        parser.error(f"two scenes would bake into {args.output / sorted(dup)[0]}: rename one")
    if args.vary:
        if args.vary < 1:
            parser.error("--vary needs at least 1")
        scenes = [v for s in scenes for v in vary(s, args.vary, args.vary_seed, args.output / "variants")]
    summary = run(scenes, args.output, address=args.address, local=args.local,
                  cpus_per_task=args.cpus_per_task, retries=args.retries, force=args.force,
                  atlas=args.atlas, progress=not args.quiet)
    print(f"{summary['ok']} baked, {summary['skipped']} up to date, {summary['failed']} failed "
          f"in {summary['seconds']:.1f} s (Ray start {summary['ray_start_seconds']:.1f} s); "
          f"{args.output / 'summary.json'}")
    return 1 if summary["failed"] else 0


if __name__ == "__main__":
    sys.exit(main())
