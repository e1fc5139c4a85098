#!/usr/bin/python3
"""btr-dem workflows (run with Debian's /usr/bin/python3).

  compare PRE.csv POST.csv -o OUTDIR      structure before/after, displacements, nonphysical BTR configurations
  pour PACKING.csv -o OUTDIR [--seed N]   reference DEM pour of a BTR packing's grains (btr pour)
  pipeline [SCENE] [-o OUTDIR]            btr settle -> comparison -> report (default inputs/bed3d.toml)
  error-vs-runtime SCENE [-o OUTDIR]      error of BTR, BTR + relaxation and DEM pours against a pour reference
  stability [-o OUTDIR] [--tiny|--full]   stiff/extreme cases run to rest; stable-step margin by bisection
  brazil-nut [-o OUTDIR] [--tiny]         intruder rise under dynamic BTR shaking, Phi sweep, 3D and 2D
  drum [-o OUTDIR] [--revolutions N]      segregation and dynamic angle in a rotating drum (2D, 3D)
  hele-shaw [-o OUTDIR] [--reduced|--tiny] angle of repose in Hele-Shaw cells (seed 003): DEM, BTR, BTR + relax, BTR + ub-relax
  nano-powder [-o OUTDIR] [--cycles N]    rigid clusters redeposited: <h> = a - b exp(-n/tau) (2D, 3D)
  stratification [-o OUTDIR] [--tiny]     two-species heap in a Hele-Shaw cell: stripes, top-toe segregation, BTR vs DEM
  settle-matrix -o OUTDIR [--count N]     btr settle against reference pours over beds and heaps (docs/settle)
  dynamic-vs-dem [-o OUTDIR] [--plan P]   dynamic BTR against DEM: drum segregation, Brazil nut, cost per revolution

The `btr` program is $BTR_BINARY, else build/app/btr. Exit status: 0 done, 2 bad input, 3 a step failed
(its error is printed and recorded in OUTDIR/run.json; what earlier steps wrote is kept)."""
from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from btrdem.core.io import InputError  # noqa: E402
from btrdem.core.runner import REPO, Interrupted, StepFailed, stop_on_signals  # noqa: E402
from btrdem.studies.error_runtime import METHODS as METHODS_DEFAULT  # noqa: E402

DEFAULT_SCENE = REPO / "inputs" / "bed3d.toml"


def progress(msg: str):
    print(msg, flush=True)


def floats(text: str) -> list:
    try:
        return [float(x) for x in text.split(",") if x]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected comma-separated numbers, got {text!r}") from None


def ints(text: str) -> list:
    try:
        out = [int(x) for x in text.split(",") if x]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected comma-separated grain counts, got {text!r}") from None
    if not out or min(out) <= 0:
        raise argparse.ArgumentTypeError(f"expected positive grain counts, got {text!r}")
    return out


def pour_variants(text: str) -> list:
    if text.strip() in ("", "none"):
        return []
    out = []
    for item in text.split(","):
        try:
            pace, stop = item.split(":")
            out.append((float(pace), float(stop)))
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected PACE:STOP_RATIO[,PACE:STOP_RATIO...], got {text!r}") from None
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="btr_workflow.py", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="command", required=True)
    margin_help = "bulk window margin from floor, walls and free surface, in largest diameters (default: btr measure's)"

    c = sub.add_parser("compare", help="compare two packings of the same grains")
    c.add_argument("pre")
    c.add_argument("post")
    c.add_argument("-o", "--out", required=True)
    c.add_argument("--scene", help="scene TOML (default: the scene in PRE's JSON)")
    c.add_argument("--margin", type=float, help=margin_help)
    c.add_argument("--contact-tolerance", type=float,
                   help="contact: gap < tolerance x smaller radius (default: btr measure's)")

    p = sub.add_parser("pour", help="reference DEM pour of a BTR packing's grains (btr pour)")
    p.add_argument("packing")
    p.add_argument("-o", "--out", required=True)
    p.add_argument("--engine", choices=["liggghts", "yade"], default="liggghts")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--np", type=int, default=1)
    p.add_argument("--pace", type=float, default=1.0, help="batch interval / batch fall time (default 1)")
    p.add_argument("--stop-ratio", type=float, help="kinetic stop ratio (default: the scene's)")

    pl = sub.add_parser("pipeline", help="btr settle (BTR -> calibration pour -> DEM relaxation) -> comparison -> report")
    pl.add_argument("scene", nargs="?", default=str(DEFAULT_SCENE))
    pl.add_argument("-o", "--out", help="output folder (default out/<scene name>)")
    pl.add_argument("--engine", choices=["liggghts", "yade"], default="liggghts")
    pl.add_argument("--np", type=int, default=1)
    pl.add_argument("--seed", type=int)
    pl.add_argument("--count", type=int)
    pl.add_argument("--calibration-grains", type=int,
                    help="grains of settle's calibration pour (default: btr settle's; fewer is cheaper and noisier)")

    e = sub.add_parser("error-vs-runtime", help="error against run time of BTR, BTR + relaxation and DEM pours")
    e.add_argument("scene")
    e.add_argument("-o", "--out", help="output folder (default out/<scene name>/error_vs_runtime)")
    e.add_argument("--engine", choices=["liggghts", "yade"], default="liggghts")
    e.add_argument("--ref-seeds", type=int, default=3)
    e.add_argument("--count", type=int, help="grains (default: the scene's)")
    e.add_argument("--relax-times", type=floats, help="relaxation caps [s], e.g. 0.01,0.05,0.2")
    e.add_argument("--pours", type=pour_variants, help="shorter pours PACE:STOP,... e.g. 0.25:1e-3,0.5:1e-4,1:1e-6")
    e.add_argument("--np", type=int, default=1)
    e.add_argument("--margin", type=float, help=margin_help)
    e.add_argument("--counts", type=ints, help="size study: the same table at each grain count, e.g. 3000,10000,30000, "
                                               "into OUT/n<N>/ with OUT/size_study.{md,json,png}")
    e.add_argument("--methods", default=",".join(METHODS_DEFAULT),
                   help="BTR-based methods besides BTR alone: some of " + ",".join(METHODS_DEFAULT))
    e.add_argument("--damping", type=float, default=0.5, help="damping of the damped method (default 0.5)")
    e.add_argument("--target-phi", default="pour",
                   help="target of the target-phi method: 'pour' (the reference pours' mean) or a number")
    e.add_argument("--friction-scales", type=floats,
                   help="target-phi methods: friction scales of the compaction, tried in turn (default btr relax's, 0)")
    e.add_argument("--compaction-damping", type=floats,
                   help="target-phi methods: damping during the compaction (default btr relax's, 0.15); a list "
                        "such as 0.1,0.15 runs each target-phi method once per value")
    e.add_argument("--compaction-timestep-fraction", type=float,
                   help="target-phi methods: time step of the compaction as a fraction of the Rayleigh / contact "
                        "time (default: the scene's timestep_fraction, the settle's)")
    e.add_argument("--shakes", type=int, default=10, help="btr shake cycles of the shake method (default 10)")
    e.add_argument("--reuse-pours", action="store_true",
                   help="reuse pours already finished in the output folder with the same settings and grains "
                        "(their recorded wall times)")

    s = sub.add_parser("stability", help="stiff and extreme cases run to rest; stable-step margin by bisection")
    s.add_argument("-o", "--out", help="output folder (default out/stability)")
    s.add_argument("--engines", default="liggghts,yade")
    s.add_argument("--cases", help="comma-separated case names (default: all)")
    size = s.add_mutually_exclusive_group()
    size.add_argument("--tiny", action="store_true", help="12 grains, one bisection step (tests)")
    size.add_argument("--full", action="store_true", help="1500-grain column, longer windows, 4 bisection steps")
    s.add_argument("--np", type=int, default=1)

    bn = sub.add_parser("brazil-nut", help="Brazil-nut effect under dynamic BTR shaking (btr shake)")
    bn.add_argument("-o", "--out", help="output folder (default out/brazil_nut)")
    bn.add_argument("--dims", default="3,2", help="dimensions, comma-separated (default 3,2)")
    bn.add_argument("--tiny", action="store_true", help="two Phi and two noise values, a few hundred grains, 6 cycles")
    bn.add_argument("--seed", type=int, default=1)

    dr = sub.add_parser("drum", help="rotating drum under dynamic BTR (btr drum): segregation, dynamic angle")
    dr.add_argument("-o", "--out", help="output folder (default out/drum)")
    dr.add_argument("--revolutions", type=float, default=3.0)
    dr.add_argument("--tiny", action="store_true", help="300 grains, 20 steps per revolution, one revolution")

    hs = sub.add_parser("hele-shaw", help="angle of repose in Hele-Shaw cells (seed 003): DEM vs BTR vs BTR + relax vs BTR + unbalanced-force relax")
    hs.add_argument("-o", "--out", help="output folder (default out/hele_shaw)")
    hs.add_argument("--reduced", action="store_true", help="4 N values, 9 widths (1.5-30 d), 4 widths for the second "
                                                         "size, cell 70 d (20 min measured on 2 shared cores)")
    hs.add_argument("--tiny", action="store_true", help="one cell of 120 grains, w = 3 d (for tests)")
    hs.add_argument("--pace", type=float, default=1.0,
                    help="pour rate: batch interval / batch free-fall time (smaller pours faster)")
    hs.add_argument("--n", type=int, help="grains at w = 3 d (skips the theta-against-N sweep)")
    hs.add_argument("--seed", type=int, default=1)

    nano = sub.add_parser("nano-powder", help="rigid clusters redeposited (btr redeposit): fit <h> = a - b exp(-n/tau)")
    nano.add_argument("-o", "--out", help="output folder (default out/nano_powder)")
    nano.add_argument("--cycles", type=int, default=12)
    nano.add_argument("--tiny", action="store_true", help="a few hundred grains, for tests")

    st = sub.add_parser("stratification", help="two-species heap in a Hele-Shaw cell (seed 000 Figs. 7-8): stripe "
                                               "wavelength and contrast, top-toe segregation, angle per species; "
                                               "BTR 2D, BTR 3D cell, DEM pours with rolling friction off and on")
    st.add_argument("-o", "--out", help="output folder (default out/stratification)")
    st.add_argument("--tiny", action="store_true", help="700 grains (233 in 2D), one seed, a 60 mm cell (for tests)")
    st.add_argument("--seeds", help="comma-separated seeds (default 1,2,3)")
    st.add_argument("--n", type=int, help="grains of the 3D cases (default 3000; 2D: a third)")

    sm = sub.add_parser("settle-matrix", help="btr settle against 3 reference pours per row: beds (friction, rolling "
                                              "friction, size ratio, cylinder) and heaps (angle; Hooke heaps are refused)")
    sm.add_argument("-o", "--out", required=True)
    sm.add_argument("--engine", choices=["liggghts", "yade"], default="liggghts")
    sm.add_argument("--count", type=int, default=3000, help="grains of a bed row (default 3000)")
    sm.add_argument("--depth", type=float, default=0.03, help="bed depth [m] the lateral size is chosen for (0.03)")
    sm.add_argument("--heap-count", type=int, default=2000, help="grains of a heap row (default 2000)")
    sm.add_argument("--yade-count", type=int, default=0,
                    help="also the base bed in YADE with this many grains (optional row; default 0: none)")
    sm.add_argument("--rows", help="comma-separated row names (default: all)")
    sm.add_argument("--ref-seeds", type=int, default=3)
    sm.add_argument("--np", type=int, default=1)
    sm.add_argument("--margin", type=float, help=margin_help)
    sm.add_argument("--reuse-pours", action="store_true",
                    help="reuse the reference pours already finished in OUT/runs with the same scene and settings")
    sm.add_argument("--reuse-settles", action="store_true",
                    help="reuse a btr settle already finished in OUT/runs/ROW/settle from the same scene and engine")
    sm.add_argument("--pours-only", action="store_true", help="the reference pours alone (no btr settle)")
    sm.add_argument("--settle-seeds", type=int, default=1,
                    help="settle each bed row at seeds 1..N (default 1): one settle's own seed-to-seed scatter beside "
                         "the pours' floor, in runs/ROW/settle_seedS")

    dv = sub.add_parser("dynamic-vs-dem", help="dynamic BTR (btr drum, btr shake) against DEM (the same commands "
                                               "with --engine): drum segregation, Brazil nut, cost (docs/dynamic_vs_dem)")
    dv.add_argument("-o", "--out", help="output folder (default out/dynamic_vs_dem)")
    dv.add_argument("--engine", choices=["liggghts", "yade"], default="liggghts",
                    help="the drum's DEM engine (the Brazil nut always taps in LIGGGHTS)")
    dv.add_argument("--plan", choices=["full", "reduced", "tiny"], default="full",
                    help="full: the issue's matrix (hours); reduced: about half an hour of 2 cores; tiny: for tests")
    dv.add_argument("--seeds", default="1,2,3", help="comma-separated seeds of each side (default 1,2,3)")
    dv.add_argument("--parts", default="drum,brazil,cost",
                    help="some of drum, brazil, cost, mapping (BTR's steps per revolution and lift swept against "
                         "the drum's DEM runs); default drum,brazil,cost")
    dv.add_argument("--np", type=int, default=1)
    dv.add_argument("--dims", default="2,3", help="the drum cases' dimensions: 2, 3 or 2,3 (default)")
    dv.add_argument("--report-only", action="store_true",
                    help="with --parts drum: tables and report from the runs finished in OUT/runs, the rest "
                         "rows 'not run'; runs nothing")
    dv.add_argument("--reuse-runs", action="store_true",
                    help="reuse the drum runs already finished in OUT/runs from the same scene and arguments")

    args = ap.parse_args(argv)
    if getattr(args, "out", None):
        # Every study runs btr and the engines inside its output folders: a relative -o must not nest.
        args.out = os.path.abspath(args.out)
    try:
        if args.command == "compare":
            from btrdem.analysis.compare import compare
            from btrdem.core.runner import RunRecord
            rec = RunRecord(args.out, "compare", inputs=[args.scene] if args.scene else [], progress=progress,
                            settings={"pre": str(Path(args.pre).resolve()), "post": str(Path(args.post).resolve()),
                                      "margin": args.margin, "contact_tolerance": args.contact_tolerance})
            with rec.step("compare"):
                res = compare(args.pre, args.post, args.out, args.scene, args.margin, args.contact_tolerance,
                              progress)
            rec.finish()
            st = res["displacement_d"]
            progress(f"moved > 0.1 d: {100 * st['fraction_above_0.1']:.3g} %, > 0.5 d: "
                     f"{100 * st['fraction_above_0.5']:.3g} %; change in packing fraction "
                     f"{res['changes']['packing_fraction']}, coordination {res['changes']['coordination_mean']}")
        elif args.command == "pour":
            from btrdem.core.io import read_packing
            from btrdem.dem.pour import PourSettings, pour
            from btrdem.core.runner import RunRecord
            settings = PourSettings(seed=args.seed, np=args.np, pace=args.pace, stop_ratio=args.stop_ratio,
                                    engine=args.engine)
            rec = RunRecord(args.out, "pour", inputs=[args.packing, str(Path(args.packing).with_suffix(".json"))],
                            progress=progress, settings=settings.__dict__)
            with rec.step(f"{args.engine} pour") as st:
                summary = pour(read_packing(args.packing), args.out, settings, progress)
                st.update(outputs=[summary["packing"]])
            rec.finish(summary)
        elif args.command == "pipeline":
            from btrdem.studies.pipeline import run_pipeline
            run_pipeline(args.scene, args.out, args.engine, args.np, args.seed, args.count, progress,
                         calibration_grains=args.calibration_grains)
        elif args.command == "error-vs-runtime":
            from btrdem.studies.error_runtime import run_error_vs_runtime, run_size_study
            if args.target_phi != "pour":
                try:
                    if not 0.0 < float(args.target_phi) < 1.0:
                        raise ValueError
                except ValueError:
                    raise InputError(f"--target-phi: expected 'pour' or a packing fraction in (0, 1), "
                                     f"got {args.target_phi!r}") from None
            kw = dict(engine=args.engine, ref_seeds=args.ref_seeds, relax_times=args.relax_times,
                      pour_variants=args.pours, ranks=args.np, margin=args.margin, progress=progress,
                      methods=[m for m in args.methods.split(",") if m], damping=args.damping,
                      target_phi=args.target_phi, shakes=args.shakes, reuse_pours=args.reuse_pours,
                      friction_scales=args.friction_scales, compaction_damping=args.compaction_damping,
                      compaction_timestep_fraction=args.compaction_timestep_fraction)
            if args.counts:
                run_size_study(args.scene, args.counts, args.out, **kw)
            else:
                run_error_vs_runtime(args.scene, args.out, count=args.count, **kw)
        elif args.command == "stability":
            from btrdem.studies.stability import run_stability
            engines = [x for x in args.engines.split(",") if x]
            bad = [x for x in engines if x not in ("liggghts", "yade")]
            if bad:
                raise InputError(f"--engines: expected liggghts and/or yade, got {', '.join(bad)}")
            from btrdem.studies.stability import build_cases
            cases = build_cases(args.tiny, args.full)
            if args.cases:
                names = [x for x in args.cases.split(",") if x]
                unknown = [x for x in names if x not in [c["name"] for c in cases]]
                if unknown:
                    raise InputError(f"--cases: unknown {', '.join(unknown)}; expected some of "
                                     f"{', '.join(c['name'] for c in cases)}")
                cases = [c for c in cases if c["name"] in names]
            run_stability(args.out, engines, args.tiny, args.full, args.np, progress, cases)
        elif args.command == "brazil-nut":
            from btrdem.studies.brazil_nut import run_brazil_nut
            dims = [x for x in args.dims.split(",") if x]
            if not dims or any(x not in ("2", "3") for x in dims):
                raise InputError(f"--dims: expected 3 and/or 2, comma-separated, got {args.dims!r}")
            run_brazil_nut(args.out, tuple(int(x) for x in dims), args.tiny, args.seed, progress)
        elif args.command == "hele-shaw":
            from btrdem.studies.hele_shaw import run_hele_shaw
            if not args.pace > 0:
                raise InputError(f"--pace: expected a positive number, got {args.pace}")
            if args.n is not None and args.n < 1:
                raise InputError(f"--n: expected a positive number of grains, got {args.n}")
            run_hele_shaw(args.out, args.reduced, args.tiny, args.pace, args.seed, progress, args.n)
        elif args.command == "drum":
            from btrdem.studies.drum import run_drum
            if not args.revolutions > 0:
                raise InputError(f"--revolutions: expected a positive number, got {args.revolutions}")
            run_drum(args.out, args.revolutions, args.tiny, progress)
        elif args.command == "nano-powder":
            from btrdem.studies.nano_powder import run_nano_powder
            if args.cycles < 3:
                raise InputError(f"--cycles: expected at least 3 cycles to fit, got {args.cycles}")
            run_nano_powder(args.out, args.cycles, args.tiny, progress)
        elif args.command == "stratification":
            from btrdem.studies.stratification import run_stratification
            seeds = None
            if args.seeds:
                try:
                    seeds = [int(x) for x in args.seeds.split(",")]
                except ValueError:
                    raise InputError(f"--seeds: expected comma-separated integers, got {args.seeds!r}") from None
            if args.n is not None and args.n < 20:
                raise InputError(f"--n: expected at least 20 grains, got {args.n}")
            run_stratification(args.out, args.tiny, seeds, args.n, progress=progress)
        elif args.command == "settle-matrix":
            from btrdem.studies.settle_matrix import run_settle_matrix
            for name in ("count", "heap_count"):
                if getattr(args, name) < 1:
                    raise InputError(f"--{name.replace('_', '-')}: expected a positive number of grains, "
                                     f"got {getattr(args, name)}")
            if args.yade_count < 0 or not args.depth > 0:
                raise InputError("--yade-count: expected 0 or more grains; --depth: expected a positive depth")
            from btrdem.studies.settle_rows import matrix_rows
            only = [x for x in (args.rows or "").split(",") if x] or None
            try:
                matrix_rows(only=only, yade_count=args.yade_count)
            except ValueError as e:
                raise InputError(f"--rows: {e}") from None
            run_settle_matrix(args.out, args.count, args.depth, args.heap_count, args.yade_count, args.engine,
                              args.ref_seeds, args.np, args.margin, args.reuse_pours, args.pours_only, only, progress,
                              reuse_settles=args.reuse_settles, settle_seeds=args.settle_seeds)
        elif args.command == "dynamic-vs-dem":
            from btrdem.studies.dynamic_vs_dem import run_dynamic_vs_dem
            try:
                seeds = [int(x) for x in args.seeds.split(",") if x]
            except ValueError:
                raise InputError(f"--seeds: expected comma-separated integers, got {args.seeds!r}") from None
            parts = [x for x in args.parts.split(",") if x]
            if not seeds or not parts or any(x not in ("drum", "brazil", "cost", "mapping") for x in parts):
                raise InputError(f"--seeds/--parts: expected seeds and some of drum, brazil, cost, mapping; got "
                                 f"{args.seeds!r}, {args.parts!r}")
            if args.np < 1:
                raise InputError(f"--np: expected a positive number of ranks, got {args.np}")
            dims = tuple(int(x) for x in args.dims.split(",") if x in ("2", "3"))
            if not dims or len(dims) != len([x for x in args.dims.split(",") if x]):
                raise InputError(f"--dims: expected 2, 3 or 2,3; got {args.dims!r}")
            run_dynamic_vs_dem(args.out, args.engine, args.plan, seeds, args.np, tuple(parts), progress,
                               reuse_runs=args.reuse_runs, dims=dims, report_only=args.report_only)
    except Interrupted as e:
        print(f"btr_workflow.py {args.command}: {e}: the program it ran was stopped; run.json and the tables "
              "record the interrupted case", file=sys.stderr)
        return 128 + e.signum
    except InputError as e:
        print(f"btr_workflow.py {args.command}: {e}", file=sys.stderr)
        return 2
    except StepFailed as e:
        print(f"btr_workflow.py {args.command}: FAILED: {e}", file=sys.stderr)
        return 3
    return 0


if __name__ == "__main__":
    stop_on_signals()  # a scheduler's SIGTERM stops the running program and records the case (not in tests' main())
    sys.exit(main())
