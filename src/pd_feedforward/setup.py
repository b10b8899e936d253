"""PD plus feedforward controller node for cablelab plants"""
from setuptools import find_packages, setup

package_name = "pd_feedforward"

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
    description="PD plus feedforward controller node for cablelab plants",
    license="Apache-2.0",
    python_requires=">=3.11",
    entry_points={"console_scripts": ["pd_feedforward = pd_feedforward.main:main"]},
)
