"""The package layout, which pyproject.toml cannot state with a pattern: one import package, ``evotol``,
whose sub-packages ``evotol.robots`` and ``evotol.cost_models`` live in the repository's ``robots/`` and
``cost_models/`` folders (the design card's top level). Installed as ``evotol.robots``, nothing a user
names ``robots.py`` or ``cost_models.py`` can shadow them. Everything else is in pyproject.toml.
"""
from setuptools import find_packages, setup

MAPPED = {"evotol.robots": "robots", "evotol.cost_models": "cost_models"}

packages = find_packages(include=["evotol", "evotol.*"])
for name, folder in MAPPED.items():
    packages += [name] + [f"{name}.{p}" for p in find_packages(folder)]

setup(packages=packages, package_dir={"evotol": "evotol", **MAPPED})
