# Copyright 2026 py_vision contributors
#
# Licensed under the Apache License, Version 2.0 (the "License");
# you may not use this file except in compliance with the License.
# You may obtain a copy of the License at
#
#     http://www.apache.org/licenses/LICENSE-2.0
#
# Unless required by applicable law or agreed to in writing, software
# distributed under the License is distributed on an "AS IS" BASIS,
# WITHOUT WARRANTIES OR CONDITIONS OF ANY KIND, either express or implied.
# See the License for the specific language governing permissions and
# limitations under the License.

from glob import glob
import os

from setuptools import find_packages, setup
from setuptools.command.install_scripts import install_scripts

package_name = 'py_vision'
executables = {
    'usbcam_publisher': 'py_vision.usbcam_publisher',
    'usbcam_subscriber': 'py_vision.usbcam_subscriber',
    'cv_bridge_test': 'py_vision.cv_bridge_test',
    'vision_step': 'py_vision.vision_step',
}

LAUNCHER = """{shebang}# {name}: the py_vision executable `ros2 run py_vision {name}` starts.
import sys

try:
    from {module} import main
except ImportError as error:
    sys.stderr.write(
        '{name}: cannot start: %s. Source your ROS 2 installation and this workspace first: '
        'source install/setup.bash (on the board: source /usr/bin/ros_setup.sh)\\n' % error)
    sys.exit(1)
sys.exit(main())
"""


class InstallLaunchers(install_scripts):
    """
    Install each executable as a short launcher instead of setuptools' entry-point script.

    setuptools' script looks the package up through importlib.metadata, which without a
    sourced workspace ends in a 20-line PackageNotFoundError traceback; the launcher imports
    the node's module directly and, when it cannot, says in one line what to source.
    """

    def run(self):
        super().run()
        for path in self.get_outputs():
            name = os.path.basename(path)
            if name not in executables:
                continue
            with open(path) as script:
                shebang = script.readline()
            with open(path, 'w') as script:
                script.write(LAUNCHER.format(shebang=shebang, name=name,
                                             module=executables[name]))


setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test']),
    # The viewer's page and the synthetic camera's description, read from beside their modules
    # in an install and in a source tree alike.
    package_data={'py_vision.viewer': ['page/*.html', 'page/*.js', 'page/*.css'],
                  'py_vision.capture': ['*.yaml']},
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
        ('share/' + package_name + '/config', glob('config/*.xml') + glob('config/*.yaml')),
        ('share/' + package_name + '/launch', glob('launch/*.launch.py')),
        # The model files (about 4.3 MB), their licence and where they came from.
        ('share/' + package_name + '/models',
         glob('models/*.tflite') + ['models/LICENSE', 'models/README.md']),
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='py_vision maintainers',
    maintainer_email='maintainers@py-vision.dev',
    description='USB camera streaming, display and a pure-Python cv_bridge for ROS 2.',
    license='Apache-2.0',
    tests_require=['pytest'],
    entry_points={
        'console_scripts': ['%s = %s:main' % item for item in executables.items()],
    },
    cmdclass={'install_scripts': InstallLaunchers},
)
