"""``cablelab layout --plant P [--tool foxglove|plotjuggler] [--bag BAG] -o FILE``: a Foxglove or
PlotJuggler layout of a plant (:mod:`cablelab.layouts`)."""
from __future__ import annotations

from ._workbench_args import add_overwrite

HELP = "write a Foxglove (JSON) or PlotJuggler (XML) layout of a plant: measured vs model, residual, tensions, estimate vs truth, 3D"


def add_arguments(p) -> None:
    from ..registry import available_plants

    p.add_argument("--plant", choices=available_plants(), required=True, help="which plant")
    p.add_argument("--tool", choices=("foxglove", "plotjuggler"), default="foxglove",
                   help="layout format: foxglove (JSON, Layouts > Import) or plotjuggler (XML, "
                        "Load Layout); default foxglove")
    p.add_argument("--bag", metavar="BAG",
                   help="take the channel and joint names from this bag (an overlay bag of compare/"
                        "diagnose --out, or any recording of the plant) instead of the plant's defaults")
    p.add_argument("--description", metavar="FILE",
                   help="plant description YAML for the names (e.g. the number of cables)")
    p.add_argument("-o", "--output", metavar="FILE", required=True, help="layout file to write")
    add_overwrite(p)


def run(args) -> int:
    from ..atomic import atomic_output
    from ..errors import CablelabError
    from ..layouts import plant_layout

    inputs = [args.bag, args.description]
    from ..atomic import check_target

    check_target(args.output, overwrite=args.overwrite, inputs=inputs, option="-o")
    bag = desc = None
    if args.bag:
        from ..bags import open_bag

        bag = open_bag(args.bag)
        if bag.description is not None and bag.description.plant != args.plant:
            raise CablelabError(f"{args.bag}: a {bag.description.plant} bag, not {args.plant}")
    if args.description:
        from ..description import load_description

        desc = load_description(args.description)
    text = plant_layout(args.plant, args.tool, bag=bag, description=desc)
    with atomic_output(args.output, overwrite=args.overwrite, inputs=inputs, option="-o") as tmp:
        tmp.write_text(text)
    print(f"{args.tool} layout of plant {args.plant} written to {args.output}")
    return 0
