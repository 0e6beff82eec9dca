"use strict";
const D = JSON.parse(document.getElementById("data").textContent);
const cv = document.getElementById("view"), g = cv.getContext("2d");
const slider = document.getElementById("step"), status = document.getElementById("status");
document.getElementById("title").textContent = D.title;
slider.max = Math.max(0, D.poses.length - 1);
let yaw = -0.6, pitch = 0.9, drag = null, timer = null;
const all = D.wire.flat().concat(D.poses.map(p => p.slice(0, 3)));
const mid = [0, 1, 2].map(k => (Math.min(...all.map(p => p[k])) + Math.max(...all.map(p => p[k]))) / 2);
const span = Math.max(1, ...[0, 1, 2].map(k => Math.max(...all.map(p => p[k])) - Math.min(...all.map(p => p[k]))));
function proj(p) {
  const x = p[0] - mid[0], y = p[1] - mid[1], z = p[2] - mid[2];
  const cy = Math.cos(yaw), sy = Math.sin(yaw), cp = Math.cos(pitch), sp = Math.sin(pitch);
  const x1 = cy * x - sy * y, y1 = sy * x + cy * y;
  const s = 0.8 * cv.width / span;
  return [cv.width / 2 + s * x1, cv.height / 2 - s * (cp * z + sp * y1)];
}
function line(pts, colour, width) {
  g.strokeStyle = colour; g.lineWidth = width; g.beginPath();
  pts.forEach((p, i) => { const q = proj(p); if (i) g.lineTo(q[0], q[1]); else g.moveTo(q[0], q[1]); });
  g.stroke();
}
function draw() {
  const k = Number(slider.value);
  g.clearRect(0, 0, cv.width, cv.height);
  D.wire.forEach(w => line(w, "#bbb", 1));
  line(D.poses.slice(0, k + 1).map(p => p.slice(0, 3)), "#1f77b4", 2);
  const p = D.poses[k];
  if (p) {
    const tip = p.slice(0, 3), axis = p.slice(3, 6);
    line([tip, tip.map((v, i) => v + 15 * axis[i])], "#d62728", 3);
    const s = D.steps[k];
    status.textContent = `step ${k} (${k + 1} of ${D.poses.length}): predicted z ${s.label[2].toFixed(2)} mm, ` +
      `rx ${s.label[3].toFixed(2)} deg, ry ${s.label[4].toFixed(2)} deg; true depth error ` +
      `${s.depth_error_mm.toFixed(3)} mm, normal error ${s.normal_error_deg.toFixed(2)} deg`;
  }
}
cv.addEventListener("mousedown", e => { drag = [e.clientX, e.clientY]; });
window.addEventListener("mouseup", () => { drag = null; });
window.addEventListener("mousemove", e => {
  if (!drag) return;
  yaw += (e.clientX - drag[0]) * 0.01;
  pitch = Math.max(-1.5, Math.min(1.5, pitch + (e.clientY - drag[1]) * 0.01));
  drag = [e.clientX, e.clientY]; draw();
});
slider.addEventListener("input", draw);
document.getElementById("play").addEventListener("click", () => {
  if (timer) { clearInterval(timer); timer = null; return; }
  timer = setInterval(() => {
    if (Number(slider.value) >= Number(slider.max)) { clearInterval(timer); timer = null; return; }
    slider.value = Number(slider.value) + 1; draw();
  }, 60);
});
const m = /#step=(\d+)/.exec(location.hash);
slider.value = m ? m[1] : slider.max;
draw();
