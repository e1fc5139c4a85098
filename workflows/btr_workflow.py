#!/usr/bin/python3
"""btr-dem workflows (run with Debian's /usr/bin/python3).

  compare PRE.csv POST.csv -o OUTDIR      structure before/after, displacements, nonphysical BTR configurations
  pour PACKING.csv -o OUTDIR [--seed N]   reference LIGGGHTS pour of a BTR packing's grains
  pipeline [SCENE] [-o OUTDIR]            BTR -> DEM relaxation -> comparison -> report (default inputs/bed3d.toml)
  error-vs-runtime SCENE [-o OUTDIR]      error of BTR, BTR + relaxation and DEM pours against a pour reference
  stability [-o OUTDIR] [--tiny]          relaxation stability sweep in each engine
  brazil-nut [-o OUTDIR] [--tiny]         intruder rise under dynamic BTR shaking, Phi sweep, 3D and 2D
  drum [-o OUTDIR] [--revolutions N]      segregation and dynamic angle in a rotating drum (2D, 3D)
  nano-powder [-o OUTDIR] [--cycles N]     rigid clusters redeposited: <h> = a - b exp(-n/tau) (2D, 3D)

The `btr` program is $BTR_BINARY, else build/app/btr. Exit status: 0 done, 2 bad input, 3 a step failed
(its error is printed and recorded in OUTDIR/run.json; what earlier steps wrote is kept)."""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from btrdem.io import InputError  # noqa: E402
from btrdem.runner import REPO, StepFailed  # noqa: E402

DEFAULT_SCENE = REPO / "inputs" / "bed3d.toml"


def progress(msg: str):
    print(msg, flush=True)


def floats(text: str) -> list:
    try:
        return [float(x) for x in text.split(",") if x]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected comma-separated numbers, got {text!r}") from None


def pour_variants(text: str) -> list:
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

    p = sub.add_parser("pour", help="reference LIGGGHTS pour of a BTR packing's grains")
    p.add_argument("packing")
    p.add_argument("-o", "--out", required=True)
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--np", type=int, default=1)
    p.add_argument("--pace", type=float, default=1.0, help="batch interval / batch fall time (default 1)")
    p.add_argument("--stop-ratio", type=float, help="kinetic stop ratio (default: the scene's)")

    pl = sub.add_parser("pipeline", help="BTR -> DEM relaxation -> comparison -> report")
    pl.add_argument("scene", nargs="?", default=str(DEFAULT_SCENE))
    pl.add_argument("-o", "--out", help="output folder (default out/<scene name>)")
    pl.add_argument("--engine", choices=["liggghts", "yade"], default="liggghts")
    pl.add_argument("--np", type=int, default=1)
    pl.add_argument("--seed", type=int)
    pl.add_argument("--count", type=int)

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

    s = sub.add_parser("stability", help="relaxation stability sweep")
    s.add_argument("-o", "--out", help="output folder (default out/stability)")
    s.add_argument("--engines", default="liggghts,yade")
    s.add_argument("--scene", help="base scene TOML (default: a small periodic bed)")
    s.add_argument("--tiny", action="store_true", help="two values per parameter, 60 grains, 3000 steps")
    s.add_argument("--max-steps", type=int)
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

    nano = sub.add_parser("nano-powder", help="rigid clusters redeposited (btr redeposit): fit <h> = a - b exp(-n/tau)")
    nano.add_argument("-o", "--out", help="output folder (default out/nano_powder)")
    nano.add_argument("--cycles", type=int, default=12)
    nano.add_argument("--tiny", action="store_true", help="a few hundred grains, for tests")

    args = ap.parse_args(argv)
    try:
        if args.command == "compare":
            from btrdem.compare import compare
            from btrdem.runner import RunRecord
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
            from btrdem.io import read_packing
            from btrdem.pour import PourSettings, pour
            from btrdem.runner import RunRecord
            settings = PourSettings(seed=args.seed, np=args.np, pace=args.pace, stop_ratio=args.stop_ratio)
            rec = RunRecord(args.out, "pour", inputs=[args.packing, str(Path(args.packing).with_suffix(".json"))],
                            progress=progress, settings=settings.__dict__)
            with rec.step("liggghts pour") as st:
                summary = pour(read_packing(args.packing), args.out, settings, progress)
                st.update(outputs=[summary["packing"]])
            rec.finish(summary)
        elif args.command == "pipeline":
            from btrdem.pipeline import run_pipeline
            run_pipeline(args.scene, args.out, args.engine, args.np, args.seed, args.count, progress)
        elif args.command == "error-vs-runtime":
            from btrdem.error_runtime import run_error_vs_runtime
            run_error_vs_runtime(args.scene, args.out, args.engine, args.ref_seeds, args.count, args.relax_times,
                                 args.pours, args.np, args.margin, progress)
        elif args.command == "stability":
            from btrdem.stability import run_stability
            engines = [x for x in args.engines.split(",") if x]
            bad = [x for x in engines if x not in ("liggghts", "yade")]
            if bad:
                raise InputError(f"--engines: expected liggghts and/or yade, got {', '.join(bad)}")
            run_stability(args.out, engines, args.scene, args.tiny, args.max_steps, args.np, progress)
        elif args.command == "brazil-nut":
            from btrdem.brazil_nut import run_brazil_nut
            dims = [x for x in args.dims.split(",") if x]
            if not dims or any(x not in ("2", "3") for x in dims):
                raise InputError(f"--dims: expected 3 and/or 2, comma-separated, got {args.dims!r}")
            run_brazil_nut(args.out, tuple(int(x) for x in dims), args.tiny, args.seed, progress)
        elif args.command == "drum":
            from btrdem.drum import run_drum
            if not args.revolutions > 0:
                raise InputError(f"--revolutions: expected a positive number, got {args.revolutions}")
            run_drum(args.out, args.revolutions, args.tiny, progress)
        elif args.command == "nano-powder":
            from btrdem.nano_powder import run_nano_powder
            if args.cycles < 3:
                raise InputError(f"--cycles: expected at least 3 cycles to fit, got {args.cycles}")
            run_nano_powder(args.out, args.cycles, args.tiny, progress)
    except InputError as e:
        print(f"btr_workflow.py {args.command}: {e}", file=sys.stderr)
        return 2
    except StepFailed as e:
        print(f"btr_workflow.py {args.command}: FAILED: {e}", file=sys.stderr)
        return 3
    return 0


if __name__ == "__main__":
    sys.exit(main())
