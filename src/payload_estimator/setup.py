"""Live payload (CDPR mass and centre of mass) and swing (crane) estimator node"""
from setuptools import find_packages, setup

package_name = "payload_estimator"

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
    description="Live payload (CDPR mass and centre of mass) and swing (crane) estimator node",
    license="Apache-2.0",
    python_requires=">=3.11",
    entry_points={"console_scripts": ["payload_estimator = payload_estimator.main:main"]},
)
