"""Live payload (CDPR mass and centre of mass) and swing (crane) estimator node (metadata in setup.cfg)."""
from setuptools import setup

setup()
