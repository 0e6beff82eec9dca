// The replay page's script (inlined by replay_html.rs): the world in mm
// with ticked axes and a scale bar, the tap's pins, the status line.
const D = JSON.parse(document.getElementById('data').textContent);
const S = D.steps, slider = document.getElementById('slider');
const status = document.getElementById('status'), play = document.getElementById('play');
const frameNote = document.getElementById('frame');
document.getElementById('title').textContent = D.title;
for (const n of D.notes) { const p = document.createElement('p'); p.textContent = n; document.getElementById('notes').appendChild(p); }
slider.max = Math.max(S.length - 1, 0);

// The world's box in mm: contour and path, one sensor radius round them,
// widened to the plot's aspect so one mm is as long on both axes.
const W = document.getElementById('world'), wc = W.getContext('2d');
const M = { l: 50, r: 12, t: 12, b: 40 }, PW = W.width - M.l - M.r, PH = W.height - M.t - M.b;
const pts = D.contour.concat(S.map(s => [s[0], s[1]]));
if (!pts.length) pts.push([0, 0]);
let x0 = Math.min(...pts.map(p => p[0])) - D.radius, x1 = Math.max(...pts.map(p => p[0])) + D.radius;
let y0 = Math.min(...pts.map(p => p[1])) - D.radius, y1 = Math.max(...pts.map(p => p[1])) + D.radius;
const k = Math.min(PW / (x1 - x0), PH / (y1 - y0));
{ const cx = (x0 + x1) / 2, cy = (y0 + y1) / 2; x0 = cx - PW / k / 2; x1 = cx + PW / k / 2; y0 = cy - PH / k / 2; y1 = cy + PH / k / 2; }
const tx = p => [M.l + (p[0] - x0) * k, M.t + PH - (p[1] - y0) * k];
// A round step (1, 2 or 5 times a power of ten) giving about `n` ticks.
function niceStep(span, n) {
  const raw = span / n, p = Math.pow(10, Math.floor(Math.log10(raw))), m = raw / p;
  return (m < 1.5 ? 1 : m < 3.5 ? 2 : m < 7.5 ? 5 : 10) * p;
}
const fmt = v => String(Math.round(v * 1e6) / 1e6);
const tickStep = niceStep(Math.max(x1 - x0, y1 - y0), 7);
const ticks = (lo, hi) => { const t = []; for (let v = Math.ceil(lo / tickStep) * tickStep; v <= hi + 1e-9; v += tickStep) t.push(v); return t; };
const xTicks = ticks(x0, x1), yTicks = ticks(y0, y1);
const barMm = niceStep(x1 - x0, 5);
W.dataset.xTicks = xTicks.map(fmt).join(' ');
W.dataset.yTicks = yTicks.map(fmt).join(' ');
W.dataset.scaleBar = fmt(barMm) + ' mm';

function line(c, a, b, col, w) { c.strokeStyle = col; c.lineWidth = w; c.beginPath(); c.moveTo(...a); c.lineTo(...b); c.stroke(); }
function poly(c, ps, col, w, close) {
  if (!ps.length) return; c.strokeStyle = col; c.lineWidth = w; c.beginPath(); c.moveTo(...ps[0]);
  for (const p of ps.slice(1)) c.lineTo(...p); if (close) c.closePath(); c.stroke();
}
function text(c, s, at, align, base) { c.fillStyle = '#444'; c.font = '12px sans-serif'; c.textAlign = align; c.textBaseline = base; c.fillText(s, ...at); }
// Grid, frame, ticks in mm, axis names and the scale bar (bottom right).
function drawAxes() {
  for (const v of xTicks) { const [x] = tx([v, y0]); line(wc, [x, M.t], [x, M.t + PH], '#eee', 1); line(wc, [x, M.t + PH], [x, M.t + PH + 5], '#666', 1); text(wc, fmt(v), [x, M.t + PH + 7], 'center', 'top'); }
  for (const v of yTicks) { const [, y] = tx([x0, v]); line(wc, [M.l, y], [M.l + PW, y], '#eee', 1); line(wc, [M.l - 5, y], [M.l, y], '#666', 1); text(wc, fmt(v), [M.l - 7, y], 'right', 'middle'); }
  wc.strokeStyle = '#666'; wc.lineWidth = 1; wc.strokeRect(M.l, M.t, PW, PH);
  text(wc, 'x (mm)', [M.l + PW / 2, W.height - 4], 'center', 'bottom');
  wc.save(); wc.translate(12, M.t + PH / 2); wc.rotate(-Math.PI / 2); text(wc, 'y (mm)', [0, 0], 'center', 'middle'); wc.restore();
  const bx = M.l + PW - 14 - barMm * k, by = M.t + PH - 14;
  wc.fillStyle = 'rgba(255,255,255,0.85)'; wc.fillRect(bx - 6, by - 20, barMm * k + 12, 28);
  line(wc, [bx, by], [bx + barMm * k, by], '#222', 3);
  line(wc, [bx, by - 4], [bx, by + 4], '#222', 1.5); line(wc, [bx + barMm * k, by - 4], [bx + barMm * k, by + 4], '#222', 1.5);
  text(wc, fmt(barMm) + ' mm', [bx + barMm * k / 2, by - 5], 'center', 'bottom');
}
function drawWorld(i) {
  wc.clearRect(0, 0, W.width, W.height);
  drawAxes();
  wc.save(); wc.beginPath(); wc.rect(M.l, M.t, PW, PH); wc.clip();
  poly(wc, D.contour.map(tx), '#999', 2, true);
  poly(wc, S.slice(0, i + 1).map(s => tx(s)), '#1f77b4', 1.5, false);
  const s = S[i];
  if (s) {
    const a = s[2] * Math.PI / 180, c = tx(s);
    wc.strokeStyle = '#d62728'; wc.lineWidth = 1.5; wc.beginPath(); wc.arc(c[0], c[1], D.radius * k, 0, 2 * Math.PI); wc.stroke();
    line(wc, c, tx([s[0] + D.radius * Math.cos(a), s[1] + D.radius * Math.sin(a)]), '#d62728', 2);
    const n = a - s[4] * Math.PI / 180, e = [s[0] - s[3] * Math.cos(n), s[1] - s[3] * Math.sin(n)];
    const t = [-Math.sin(n), Math.cos(n)], h = D.radius * 0.8;
    line(wc, tx([e[0] - h * t[0], e[1] - h * t[1]]), tx([e[0] + h * t[0], e[1] + h * t[1]]), '#ff7f0e', 3);
  }
  wc.restore();
}
const P = document.getElementById('pins'), pc = P.getContext('2d');
const imgs = D.images.map(u => { const im = new Image(); im.onload = () => show(+slider.value); im.src = u; return im; });
function drawPins(i) {
  pc.clearRect(0, 0, P.width, P.height);
  const f = D.fields[i], im = imgs[D.step_image[i]];
  let q, ox = 20, oy = 20, px0 = 0, py0 = 0;
  if (im && im.complete && im.naturalWidth) {
    q = Math.min(P.width / im.naturalWidth, P.height / im.naturalHeight); ox = 0; oy = 0;
    pc.globalAlpha = 0.45; pc.drawImage(im, 0, 0, im.naturalWidth * q, im.naturalHeight * q); pc.globalAlpha = 1;
  }
  if (!D.pins.length || !f || !f.length) { pc.fillStyle = '#888'; pc.font = '14px sans-serif'; pc.fillText('no pin displacements kept for this run', 20, 30); return; }
  const xs = D.pins.map(p => p[0]), ys = D.pins.map(p => p[1]);
  if (!q) { px0 = Math.min(...xs); py0 = Math.min(...ys); q = (P.width - 40) / Math.max(Math.max(...xs) - px0, Math.max(...ys) - py0); }
  const m = D.pins.length;
  for (let j = 0; j < m; j++) {
    const p = [ox + (D.pins[j][0] - px0) * q, oy + (D.pins[j][1] - py0) * q];
    pc.fillStyle = '#bbb'; pc.beginPath(); pc.arc(p[0], p[1], 2.5, 0, 2 * Math.PI); pc.fill();
    line(pc, p, [p[0] + 3 * q * f[j], p[1] + 3 * q * f[m + j]], '#2ca02c', 1.5);
  }
}
// The frame that answered step i's tap, by image name, and its label distance.
function frameText(i) {
  const name = D.image_names[D.step_image[i]];
  if (name === undefined) return '';
  const d = D.step_distance[i];
  return `answered by the real frame ${name}` + (d === null || d === undefined ? '' : `, label distance ${d.toFixed(3)}`);
}
function show(i) {
  i = Math.max(0, Math.min(S.length - 1, i | 0)); slider.value = i;
  drawWorld(i); drawPins(i);
  const s = S[i] || [0, 0, 0, 0, 0, 0, 0];
  status.dataset.step = i;
  status.textContent = `step ${i} (${i + 1} of ${S.length}): x ${s[0].toFixed(2)} mm, y ${s[1].toFixed(2)} mm, angle ${s[2].toFixed(1)} deg | predicted r ${s[3].toFixed(2)} mm, theta ${s[4].toFixed(1)} deg | mean |d| ${s[5].toFixed(2)} px, ${s[6] ? 'contact' : 'no contact'}`;
  frameNote.textContent = frameText(i);
}
let timer = null;
play.onclick = () => {
  if (timer) { clearInterval(timer); timer = null; play.textContent = 'Play'; return; }
  if (+slider.value >= S.length - 1) show(0);
  play.textContent = 'Pause';
  timer = setInterval(() => { if (+slider.value >= S.length - 1) { play.onclick(); return; } show(+slider.value + 1); }, 60);
};
slider.oninput = () => show(+slider.value);
const hash = /step=(\d+)/.exec(location.hash + location.search);
show(hash ? +hash[1] : S.length - 1);
