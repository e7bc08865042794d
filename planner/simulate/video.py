"""An mp4 of a replay's frames (H.264, yuv420p: what every player reads), encoded in
memory by PyAV (FFmpeg's libraries, shipped in the ``av`` wheel: no ffmpeg program
needed) and written by ``planner.output.write_file`` (a regular file complete or absent;
a FIFO, a device or a symlink's target written in place, never replaced).

The same frames give the same bytes: no creation time is written (FFmpeg's mp4 muxer
writes zero without one) and the encoder runs one thread.
"""

from __future__ import annotations

import io
from collections.abc import Iterable
from fractions import Fraction

import numpy as np

from planner.errors import InputError

CODEC = "libx264"
CRF = "23"  # x264's default quality (constant rate factor)
MISSING = "--video needs PyAV: pip install -e \".[physics]\""


def _av():
    try:
        import av
    except ImportError:
        raise InputError(MISSING) from None
    return av


def require() -> None:
    """InputError (exit 2) now, before any work, when the encoder is missing."""
    _av()


def encode_mp4(frames: Iterable[np.ndarray], fps: float) -> bytes:
    """The mp4 file (bytes) of ``frames`` (each (H, W, 3) uint8, H and W even) at ``fps``."""
    av = _av()
    buf = io.BytesIO()
    rate = Fraction(fps).limit_denominator(1000)
    with av.open(buf, mode="w", format="mp4") as out:
        stream = None
        for img in frames:
            img = np.ascontiguousarray(img, dtype=np.uint8)
            if stream is None:
                stream = out.add_stream(CODEC, rate=rate)
                stream.height, stream.width = img.shape[0], img.shape[1]
                stream.pix_fmt = "yuv420p"
                stream.codec_context.thread_count = 1
                stream.options = {"crf": CRF}
            frame = av.VideoFrame.from_ndarray(img, format="rgb24")
            out.mux(stream.encode(frame))
        if stream is None:
            raise InputError("no frame to write in the video")
        out.mux(stream.encode(None))
    return buf.getvalue()


def write_mp4(path: str, frames: Iterable[np.ndarray], fps: float) -> str:
    from planner.output import write_file

    write_file(path, encode_mp4(frames, fps))
    return path
