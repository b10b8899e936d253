"""ROS-free core of cablelab: plant models, effects, estimation, identification, diagnosis, bag I/O and the cablelab command line (metadata in setup.cfg)."""
from setuptools import setup

setup()
