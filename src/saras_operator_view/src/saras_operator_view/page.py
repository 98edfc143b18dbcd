"""The operator view page: HTML with inline style and a same-origin script (no external JS/CDN).

The augmented stereo is two <img> elements on the MJPEG streams; the rest is filled from the
Server-Sent Events of /events (EventSource reconnects by itself when the node restarts).
"""
import html as _html

_PAGE = """<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>%(title)s</title>
<meta name="viewport" content="width=device-width, initial-scale=1">
<style>
body{margin:0;background:#181818;color:#e8e8e8;font:14px sans-serif}
header{display:flex;justify-content:space-between;padding:6px 12px;background:#262626}
#link.live{color:#6c6}#link.down{color:#e55}
.stereo{display:flex;gap:6px;padding:6px}
figure{margin:0;flex:1;min-width:0}
figure img{width:100%%;background:#000;aspect-ratio:16/9;display:block}
figcaption{font-size:12px;color:#aaa}
.panels{display:flex;flex-wrap:wrap;gap:12px;padding:6px 12px}
section{background:#222;padding:8px 12px;border-radius:4px;min-width:220px}
h2{font-size:14px;margin:0 0 6px 0}
table{border-collapse:collapse}td{padding:2px 8px}
.swatch{display:inline-block;width:14px;height:14px;border-radius:3px;vertical-align:middle}
.OK{color:#6c6}.WARN{color:#ec4}.ERROR{color:#e55}.STALE{color:#999}
.bar{display:inline-block;height:10px;background:#48c;vertical-align:middle}
</style></head>
<body>
<header><b>%(title)s</b><span>read-only view &middot; <span id="link" class="down">connecting</span></span></header>
<div class="stereo">
<figure><img id="eye-left" src="/stream/left.mjpg" alt="left augmented endoscope">
<figcaption>left eye &middot; frames <span id="frames-left">0</span></figcaption></figure>
<figure><img id="eye-right" src="/stream/right.mjpg" alt="right augmented endoscope">
<figcaption>right eye &middot; frames <span id="frames-right">0</span></figcaption></figure>
</div>
<div class="panels">
<section><h2>Tool distances</h2><table id="tools"></table><div id="thresholds"></div></section>
<section><h2>Energy tanks</h2><table id="tanks"></table></section>
<section><h2>Component health</h2><table id="health"></table></section>
</div>
<script src="/app.js"></script>
</body></html>
"""

SCRIPT = r"""'use strict';
function cell(text, cls) {
  const td = document.createElement('td');
  td.textContent = text;
  if (cls) td.className = cls;
  return td;
}
function fill(id, rows) {
  const table = document.getElementById(id);
  table.replaceChildren(...rows.map(cells => {
    const tr = document.createElement('tr');
    cells.forEach(c => tr.appendChild(c));
    return tr;
  }));
}
function num(v, digits, unit) { return v === null ? 'no data' : v.toFixed(digits) + ' ' + unit; }
function show(s) {
  for (const eye of ['left', 'right'])
    document.getElementById('frames-' + eye).textContent = s.frames[eye].count;
  fill('tools', s.tools.map(t => {
    const sw = cell('');
    const box = document.createElement('span');
    box.className = 'swatch';
    box.style.background = t.colour;
    sw.appendChild(box);
    const d = cell(num(t.distance_mm, 1, 'mm'));
    d.dataset.tool = t.tool;
    d.dataset.region = t.region;
    return [sw, cell(t.tool), d, cell(t.region)];
  }));
  document.getElementById('thresholds').textContent =
    'collision \u2264 ' + s.thresholds_mm.collision + ' mm, warning < ' + s.thresholds_mm.warning + ' mm';
  fill('tanks', s.tanks.map(t => {
    const bar = cell('');
    const b = document.createElement('span');
    b.className = 'bar';
    b.style.width = (t.energy_j === null ? 0 : Math.max(0, Math.min(150, 5 * t.energy_j))) + 'px';
    bar.appendChild(b);
    return [cell(t.tank), cell(num(t.energy_j, 2, 'J')), bar];
  }));
  fill('health', s.health.length ? s.health.map(h => [cell(h.level, h.level), cell(h.name), cell(h.message)])
                                 : [[cell('no /diagnostics_agg yet', 'STALE')]]);
}
const link = document.getElementById('link');
const events = new EventSource('/events');
events.onmessage = e => { link.textContent = 'live'; link.className = 'live'; show(JSON.parse(e.data)); };
events.onerror = () => { link.textContent = 'disconnected'; link.className = 'down'; };
// an image stream that ended (node restarted) is reopened
for (const eye of ['left', 'right']) {
  const img = document.getElementById('eye-' + eye);
  img.onerror = () => setTimeout(() => { img.src = '/stream/' + eye + '.mjpg?t=' + Date.now(); }, 2000);
}
"""


def html(title):
    """The page with ``title`` (escaped)."""
    return _PAGE % {'title': _html.escape(title)}
