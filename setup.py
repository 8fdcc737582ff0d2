# The Python package gear_dynamics (python/gear_dynamics), installed by catkin_python_setup().
from setuptools import setup
from catkin_pkg.python_setup import generate_distutils_setup

setup(**generate_distutils_setup(packages=["gear_dynamics"], package_dir={"": "python"}))
