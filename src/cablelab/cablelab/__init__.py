"""cablelab: model-vs-measurement workbench for cable-driven robots and cranes (ROS-free core).

The names a script needs, importable from here (each is defined once, in the module named
beside it)::

    import cablelab

    plant, desc, ds = cablelab.load("run.mcap")                  # bag -> plant, description, dataset
    model = cablelab.build_model(plant, desc)                    # the plant's nominal model
    d = cablelab.find_missing_effects(ds, model, plant.candidates(desc), greedy_mode=True)
    d.ranking[0].effect, d.ranking[0].params                     # a Diagnosis of Candidates
    cablelab.compare(ds, model).channels                         # a Comparison
    cablelab.identify_report(ds, model).params                   # an IdentifyReport
    cablelab.build_report(ds, d, "report_dir")                   # index.html + figures

``find_missing_effects`` is :func:`cablelab.workbench.diagnose` (``cablelab.diagnose`` is the
diagnosis package). The names are loaded on first use, so ``import cablelab`` stays light for
the ROS nodes and the command line.
"""
from __future__ import annotations

import importlib

from .description import Description, load_description
from .errors import CablelabError

#: public name -> (module, name in that module)
_LAZY = {
    "load": ("cablelab.workbench", "load"),
    "build_model": ("cablelab.workbench", "build_model"),
    "compare": ("cablelab.workbench", "compare"),
    "identify_report": ("cablelab.workbench", "identify_report"),
    "find_missing_effects": ("cablelab.workbench", "diagnose"),
    "build_report": ("cablelab.report", "build_report"),
    "ReportPage": ("cablelab.report", "ReportPage"),
    "Diagnosis": ("cablelab.diagnose.result", "Diagnosis"),
    "Candidate": ("cablelab.diagnose.result", "Candidate"),
    "Step": ("cablelab.diagnose.result", "Step"),
    "Comparison": ("cablelab.results", "Comparison"),
    "FitQuality": ("cablelab.results", "FitQuality"),
    "IdentifyReport": ("cablelab.results", "IdentifyReport"),
    "Model": ("cablelab.model", "Model"),
    "Dataset": ("cablelab.dataset", "Dataset"),
    "available_plants": ("cablelab.registry", "available_plants"),
    "get_plant": ("cablelab.registry", "get_plant"),
}

__all__ = ["CablelabError", "Description", "load_description", *_LAZY]
__version__ = "0.1.0"


def __getattr__(name: str):
    try:
        module, attr = _LAZY[name]
    except KeyError:
        raise AttributeError(f"module 'cablelab' has no attribute {name!r}") from None
    value = getattr(importlib.import_module(module), attr)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))
