"""Example machines of the ``mjcf`` plant, shipped as MJCF files (README.md of the plant)."""
from pathlib import Path

HERE = Path(__file__).resolve().parent
#: a three-joint arm (base yaw, shoulder, elbow) carrying an unknown payload on ``tool``
ARM3 = HERE / "arm3.xml"
#: an overhead crane: driven trolley and hoist, a payload swinging freely on the rope
GANTRY = HERE / "gantry.xml"
#: a four-cable camera robot: a carriage on four cables over pulleys (spatial tendons)
CABLECAM = HERE / "cablecam.xml"


def text(path: Path) -> str:
    """The model text of an example."""
    return Path(path).read_text(encoding="utf-8")
