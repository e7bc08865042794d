"""A self-contained HTML page of a replay's frames: every frame a JPEG inlined as base64,
shown one at a time with play/pause, a scrub bar, a speed choice and the frame's time;
the physics report's summary beneath. No script or style from outside the page: it
works offline, from the file alone. The same frames and report give the same bytes.
"""

from __future__ import annotations

import base64
import html
import io
import json

import numpy as np

JPEG_QUALITY = 70  # Pillow's JPEG quality

_SCRIPT = """
const frames = JSON.parse(document.getElementById("frames").textContent);
const times = JSON.parse(document.getElementById("times").textContent);
const fps = %(fps)s;
const img = document.getElementById("frame"), bar = document.getElementById("scrub");
const label = document.getElementById("time"), button = document.getElementById("play");
const speed = document.getElementById("speed");
let i = 0, timer = null;
function show(k) {
  i = Math.max(0, Math.min(frames.length - 1, k));
  img.src = "data:image/jpeg;base64," + frames[i];
  bar.value = i;
  label.textContent = "t = " + times[i].toFixed(2) + " s  (frame " + (i + 1) + " / " +
    frames.length + ")";
}
function stop() { if (timer !== null) { clearInterval(timer); timer = null; } button.textContent = "play"; }
function play() {
  stop();
  if (i >= frames.length - 1) show(0);
  button.textContent = "pause";
  timer = setInterval(() => { if (i >= frames.length - 1) stop(); else show(i + 1); },
                      1000 / (fps * parseFloat(speed.value)));
}
button.onclick = () => (timer === null ? play() : stop());
speed.onchange = () => { if (timer !== null) play(); };
bar.oninput = () => { stop(); show(parseInt(bar.value, 10)); };
document.onkeydown = (e) => {
  if (e.key === " ") { e.preventDefault(); button.onclick(); }
  else if (e.key === "ArrowRight") { stop(); show(i + 1); }
  else if (e.key === "ArrowLeft") { stop(); show(i - 1); }
};
show(0);
"""


def frame_jpeg(img: np.ndarray) -> bytes:
    """One frame (H, W, 3) uint8 as JPEG bytes."""
    from PIL import Image

    buf = io.BytesIO()
    Image.fromarray(np.ascontiguousarray(img, dtype=np.uint8)).save(
        buf, format="JPEG", quality=JPEG_QUALITY)
    return buf.getvalue()


def page_html(title: str, summary: str, jpegs: list[bytes], times_s, fps: float) -> str:
    """The page (see the module docstring): ``jpegs`` the frames, ``times_s`` their
    times in the replay (s), played at ``fps``."""
    if not jpegs:
        raise ValueError("a page needs at least one frame")
    b64 = json.dumps([base64.b64encode(j).decode("ascii") for j in jpegs])
    times = json.dumps([round(float(t), 4) for t in times_s])
    speeds = "".join(f'<option value="{s}"{" selected" if s == 1 else ""}>{s}x</option>'
                     for s in (0.1, 0.25, 0.5, 1, 2))
    return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>{html.escape(title)}</title>
<style>body{{font-family:sans-serif;margin:1em;background:#fafafa}}
#frame{{display:block;max-width:100%;background:#000}}
.controls{{margin:0.5em 0;display:flex;gap:0.8em;align-items:center}}
#scrub{{flex:1}} pre{{background:#fff;border:1px solid #ddd;padding:0.6em;overflow:auto}}</style>
</head><body>
<h3>{html.escape(title)}</h3>
<p>Left: the plan as the kinematic check replays it; right: the physics replay. Keys: green
down for a note, red down where no note sounds, amber a note's key left up.</p>
<img id="frame" alt="replay frame" width="{_width(jpegs[0])}">
<div class="controls"><button id="play">play</button>
<input id="scrub" type="range" min="0" max="{len(jpegs) - 1}" value="0" step="1">
<select id="speed">{speeds}</select><span id="time"></span></div>
<pre>{html.escape(summary)}</pre>
<script type="application/json" id="frames">{b64}</script>
<script type="application/json" id="times">{times}</script>
<script>{_SCRIPT % {"fps": f"{float(fps):.6g}"}}</script>
</body></html>
"""


def _width(jpeg: bytes) -> int:
    from PIL import Image

    with Image.open(io.BytesIO(jpeg)) as im:
        return int(im.size[0])
