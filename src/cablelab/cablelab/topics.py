"""The contract topics of each plant (CONTRACT section 2) with their message types.

ROS-free: used by the recorder to pick a plant's topic set and by tools that check bags. Each
plant declares its own set (:attr:`cablelab.registry.Plant.contract_topics`, additions beyond the
contract tables documented in docs/nodes.md); this module adds the topics every plant shares.
"""
from __future__ import annotations

from .registry import available_plants, get_plant

COMMON = {
    "/clock": "rosgraph_msgs/msg/Clock",
    "/plant_description": "std_msgs/msg/String",
}


def plant_topics(plant: str) -> dict[str, str]:
    """All topics (name -> type) a recording of ``plant`` should hold, /clock and
    /plant_description included.

    Raises:
        CablelabError: unknown plant.
    """
    return {**COMMON, **get_plant(plant).contract_topics}


def all_plant_topics() -> dict[str, dict[str, str]]:
    """plant -> its contract topics (without the common ones), for every plant found."""
    return {p: dict(get_plant(p).contract_topics) for p in available_plants()}
