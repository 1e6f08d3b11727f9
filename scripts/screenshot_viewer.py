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

"""
Make docs/viewer.png (or, with --panel, docs/panel.png): the browser viewer and its camera panel.

Runs the installed usbcam_publisher (video_device:=synthetic) and usbcam_subscriber
(display:=web) on a private ROS domain, opens the page in headless Chromium and saves a
screenshot once the stats are live. With --panel the viewer listens as on a headless board
(web_host:=0.0.0.0, opened through its token URL), the brightness slider is moved first and
the whole panel is in the picture. Needs `scripts/setup.sh --test` and Debian's `chromium`
(or CHROMIUM=/path/to/chromium).

Usage: .venv/bin/python scripts/screenshot_viewer.py [--panel] [output.png]
"""

import os
from pathlib import Path
import re
import shutil
import sys
import tempfile

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / 'py_vision' / 'test'))

import ros_harness  # noqa: E402 (the test helpers that start the installed nodes)
from playwright.sync_api import sync_playwright  # noqa: E402,I100

CHROMIUM_ARGS = ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic',
                 '--no-first-run', '--disable-background-networking',
                 '--disable-component-update', '--disable-sync']


def main():
    args = sys.argv[1:]
    panel = '--panel' in args
    args = [arg for arg in args if arg != '--panel']
    output = Path(args[0]) if args else REPO / 'docs' / ('panel.png' if panel else 'viewer.png')
    chromium = (os.environ.get('CHROMIUM') or shutil.which('chromium') or
                shutil.which('chromium-browser'))
    if chromium is None:
        sys.exit('chromium is not installed (apt-get install chromium)')
    domain = ros_harness.DomainId()
    # The nodes' rcl log files go to a directory of this run, deleted at its end.
    log_dir = tempfile.mkdtemp(prefix='py_vision_screenshot_log_')
    env = ros_harness.installed_env()
    env.update(ROS_DOMAIN_ID=str(domain.value), ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST',
               PYTHONUNBUFFERED='1', RCUTILS_COLORIZED_OUTPUT='0', ROS_LOG_DIR=log_dir)
    nodes = [
        ros_harness.NodeProcess('usbcam_publisher', ros_harness.ros_args(
            {'video_device': 'synthetic', 'framerate': 15.0}), env),
        ros_harness.NodeProcess('usbcam_subscriber', ros_harness.ros_args(
            dict({'display': 'web', 'web_port': 0}, **(
                {'web_host': '0.0.0.0'} if panel else {}))), env),
    ]
    try:
        url = nodes[1].wait_for_output(r'viewer at (http://\S+:\d+/\S*)').group(1)
        # The page as a laptop on the network sees it (the host name resolves to this machine).
        url = re.sub(r'^http://[^/]+:', 'http://127.0.0.1:', url)
        with sync_playwright() as playwright, tempfile.TemporaryDirectory() as profile:
            browser = playwright.chromium.launch_persistent_context(
                profile, executable_path=chromium, headless=True, args=CHROMIUM_ARGS,
                viewport={'width': 1100, 'height': 930} if panel else {
                    'width': 1000, 'height': 790}, device_scale_factor=1)
            page = browser.new_page()
            page.goto(url)
            if panel:
                slider = page.locator('#input-brightness')
                slider.wait_for(state='visible', timeout=30000)
                box = slider.bounding_box()
                page.mouse.click(box['x'] + box['width'] * 0.6, box['y'] + box['height'] / 2)
            # Wait for a full stats window, so fps and latency are steady numbers.
            ros_harness.wait_until(
                lambda: page.locator('#stat-frames').inner_text() not in ('', '-') and
                int(page.locator('#stat-frames').inner_text()) >= 75,
                30.0, interval=0.2, what='the page to show live stats')
            output.parent.mkdir(parents=True, exist_ok=True)
            page.screenshot(path=str(output), full_page=panel)
            browser.close()
        print('wrote %s' % output)
    finally:
        for node in nodes:
            node.stop()
            node.kill()
        domain.release()
        shutil.rmtree(log_dir, ignore_errors=True)


if __name__ == '__main__':
    main()
