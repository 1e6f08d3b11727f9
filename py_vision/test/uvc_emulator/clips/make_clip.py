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
Make the H.264 clip the emulated cameras and the video tests use (run once; its output is kept).

The frames are the synthetic camera's picture (`synthetic_frame`): frame i of the clip shows
index i in its code, so a test reads back which frame it got and in what order. They are
encoded with Debian's ffmpeg and libx264 (``apt-get install ffmpeg``) as a UVC camera sends
H.264: Annex B, an access unit delimiter before each frame, no B-frames (constrained baseline),
the SPS and PPS before every IDR, an IDR every `--keyint` frames and no SEI. The tests need
neither ffmpeg nor this script.

    python3 make_clip.py --out synthetic_640x480.h264    # with py_vision importable
"""

import argparse
import subprocess
import sys

import numpy as np
from py_vision.capture.synthetic_picture import synthetic_frame


def main(argv=None):
    """Encode the clip; return the exit status."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--out', required=True, help='the .h264 file to write')
    parser.add_argument('--size', default='640x480', help='WIDTHxHEIGHT (640x480)')
    parser.add_argument('--frames', type=int, default=60, help='frames in the clip (60)')
    parser.add_argument('--keyint', type=int, default=15, help='frames from IDR to IDR (15)')
    parser.add_argument('--crf', type=int, default=23, help="x264's quality (23)")
    args = parser.parse_args(argv)
    width, height = (int(n) for n in args.size.split('x'))
    x264 = ('keyint=%d:min-keyint=%d:scenecut=0:bframes=0:aud=1:repeat-headers=1:threads=1'
            % (args.keyint, args.keyint))
    command = ['ffmpeg', '-hide_banner', '-loglevel', 'error', '-y',
               '-f', 'rawvideo', '-pix_fmt', 'bgr24', '-s', '%dx%d' % (width, height),
               '-r', '30', '-i', '-',
               '-c:v', 'libx264', '-pix_fmt', 'yuv420p', '-profile:v', 'baseline',
               '-crf', str(args.crf), '-preset', 'medium', '-x264-params', x264,
               # x264 writes its settings as an SEI in the first frame: cameras do not.
               '-bsf:v', 'filter_units=remove_types=6', '-f', 'h264', args.out]
    encoder = subprocess.Popen(command, stdin=subprocess.PIPE)
    for index in range(args.frames):
        encoder.stdin.write(np.ascontiguousarray(synthetic_frame(index, width, height)).data)
    encoder.stdin.close()
    return encoder.wait()


if __name__ == '__main__':
    sys.exit(main())
