"""python -m softhap [FOLDER]: print where the C library was loaded from and run softhap.demo()."""

import argparse

from . import build_features, library_path, version_string, SH_VERSION
from .demo import demo


def main() -> None:
    parser = argparse.ArgumentParser(prog="python -m softhap", description=__doc__.splitlines()[0])
    parser.add_argument("folder", nargs="?", default="softhap-demo", help="where the frames go (default softhap-demo)")
    parser.add_argument("--seconds", type=float, default=2.0, help="simulated time (default 2 s)")
    args = parser.parse_args()
    print("softhap %s, C library %s, features: %s" % (version_string(SH_VERSION), library_path,
                                                        ", ".join(sorted(build_features())) or "none"))
    demo(args.folder, seconds=args.seconds)


if __name__ == "__main__":
    main()
