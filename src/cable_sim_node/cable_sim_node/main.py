"""Entry point of the cable_sim_node node (filled by the foundation work)."""
import argparse
import sys


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="cable_sim_node")
    parser.add_argument("--plant", choices=["cdpr", "crane", "axis"], required=True)
    parser.parse_known_args(argv)
    return 0


if __name__ == "__main__":
    sys.exit(main())
