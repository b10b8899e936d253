"""ROS-free core of cablelab: plant models, effects, estimation, identification, diagnosis, bag I/O and the cablelab command line"""
from setuptools import find_packages, setup

package_name = "cablelab"

setup(
    name=package_name,
    version="0.1.0",
    packages=find_packages(exclude=["test", "test.*"]),
    data_files=[
        ("share/ament_index/resource_index/packages", ["resource/" + package_name]),
        ("share/" + package_name, ["package.xml"]),
    ],
    package_data={package_name: ["data/*"]},
    include_package_data=True,
    install_requires=["setuptools"],
    zip_safe=False,
    description="ROS-free core of cablelab: plant models, effects, estimation, identification, diagnosis, bag I/O and the cablelab command line",
    license="Apache-2.0",
    python_requires=">=3.11",
    entry_points={"console_scripts": ["cablelab = cablelab.cli:main"]},
)
