"""Entry point of the pd_feedforward node (filled by the foundation work)."""
import argparse
import sys


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="pd_feedforward")
    parser.add_argument("--plant", choices=["cdpr", "crane", "axis"], required=True)
    parser.parse_known_args(argv)
    return 0


if __name__ == "__main__":
    sys.exit(main())
