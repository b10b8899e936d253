"""PD plus feedforward controller node for cablelab plants (metadata in setup.cfg)."""
from setuptools import setup

setup()
