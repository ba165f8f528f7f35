#!/usr/bin/env python3
"""Submits ssgi over a shot to OpenCue: one pyoutline Shell layer, one frame chunk per task.

    python3 tests/farm/ssgi_opencue.py INPUT OUTPUT FRAMES [CHUNK]
    python3 tests/farm/ssgi_opencue.py /shows/x/renders/sh010.####.exr \\
        /shows/x/comp/sh010.####.exr 1001-1100 10

Needs pyoutline and pycue (OpenCue's Python packages) configured for your cuebot. With
use_pycuerun=False the layer's command goes to the cue as it is, and cuebot replaces its
tokens for each task: #FRAMESPEC# becomes the frames of the task's chunk in the layer's range
("1001-1010", the short last chunk "1091-1100", "1001-1019x2" for a range with a step), the
frame-list syntax ssgi's --frames reads. #FRAMESPEC# rather than #FRAME_START#-#FRAME_END#:
before OpenCue's fix #1467 (2024) #FRAME_END# ran past the end of the range in a short last
chunk. Any chunking writes the same bits as one run over the shot. ssgi takes its thread count
from CUE_THREADS, which cuebot sets from the cores the task was given. ssgi's pattern
characters (####) are not tokens: cuebot replaces only the #NAME# words it knows. RQD runs
the command, joined by spaces, as a /bin/sh script, hence the quoted paths.
"""

import getpass
import shlex
import sys

import outline
import outline.cuerun
import outline.modules.shell


def main(argv):
    if len(argv) not in (4, 5):
        sys.exit("usage: ssgi_opencue.py INPUT OUTPUT FRAMES [CHUNK]")
    input_pattern, output_pattern, frames = argv[1:4]
    chunk = int(argv[4]) if len(argv) == 5 else 10

    job = outline.Outline("ssgi", shot="sh010", show="testing", user=getpass.getuser())
    job.add_layer(
        outline.modules.shell.Shell(
            "gi",
            command=["ssgi", "run", shlex.quote(input_pattern),
                     "-o", shlex.quote(output_pattern), "--frames", "#FRAMESPEC#",
                     "--skip-existing"],
            range=frames,
            chunk=chunk,
            cores=4,
            threadable=True,
        )
    )
    outline.cuerun.launch(job, use_pycuerun=False)


if __name__ == "__main__":
    main(sys.argv)
