"""cablelab: model-vs-measurement workbench for cable-driven robots and cranes (ROS-free core).

Public surface (see docs/): plant descriptions (:mod:`cablelab.description`), bags
(:mod:`cablelab.bags`), plants, effects, identification, diagnosis and reports.
"""
from .description import Description, load_description
from .errors import CablelabError

__all__ = ["CablelabError", "Description", "load_description"]
__version__ = "0.1.0"
