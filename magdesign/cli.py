"""The ``magdesign`` command (also ``python -m magdesign``)."""

import argparse
import sys


def build_parser():
    parser = argparse.ArgumentParser(prog="magdesign", description="Design magnetic tactile sensors.")
    sub = parser.add_subparsers(dest="command", required=True)
    solve = sub.add_parser("solve", help="solve a design (default: the seed-001 dome with a Hall sensor)")
    solve.add_argument("spec", nargs="?", help="design spec (TOML)")
    solve.add_argument("--json", action="store_true", help="print one JSON object")
    return parser


def main(argv=None):
    args = build_parser().parse_args(argv)
    if args.command == "solve":
        from magdesign.fields.cylinder import report_saturation_distance  # placeholder until design/

        print(report_saturation_distance())
        return 0
    return 2


if __name__ == "__main__":
    sys.exit(main())
