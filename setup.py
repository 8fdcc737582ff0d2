# The Python package gear_dynamics (python/gear_dynamics), installed by catkin_python_setup().
from setuptools import setup
from catkin_pkg.python_setup import generate_distutils_setup

# install_requires mirrors package.xml's exec_depend for a pip view of the same dependencies.
setup(**generate_distutils_setup(packages=["gear_dynamics"], package_dir={"": "python"},
                                 install_requires=["numpy", "PyYAML", "pandas", "tqdm"]))
