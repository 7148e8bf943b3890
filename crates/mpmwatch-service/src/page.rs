//! The status page at `/`: every controller's MI matrix as a heat map (cell colour = statistic
//! over its critical value; a red frame while the channel's alarm is raised) and, for the cell
//! chosen (click one; by default the first alarmed or significant), MI and the cross-correlation
//! against lag with their critical values, the p-value's trend over recent runs against alpha,
//! and the controller's alarm history. Refreshed every few seconds from the JSON API
//! (`/profile`, `/trend`, `/alarms`). Plain HTML, CSS and inline SVG drawn by one small script:
//! no dependencies, no CDN.

/// The page.
pub const INDEX: &str = r##"<!doctype html>
<html lang="en">
<head>
<meta charset="utf-8">
<title>mpmwatch</title>
<style>
body { font: 14px/1.4 system-ui, sans-serif; margin: 1.5em; color: #222; background: #fafafa; }
h1 { font-size: 1.3em; margin: 0 0 .2em; }
.sub { color: #666; margin-bottom: 1em; }
.ctl { background: #fff; border: 1px solid #ddd; border-radius: 6px; padding: 1em; margin-bottom: 1.2em; }
.ctl h2 { font-size: 1.1em; margin: 0 0 .4em; }
.bad { color: #b00; font-weight: bold; }
.ok { color: #070; }
table.m { border-collapse: separate; border-spacing: 3px; margin: .6em 0; }
table.m th { font-weight: normal; color: #555; padding: 2px 6px; }
table.m td { width: 7.5em; height: 3.2em; text-align: center; border-radius: 4px; border: 3px solid transparent; font-size: 12px; }
table.m td.alarm { border-color: #d00; }
.legend { font-size: 12px; color: #666; }
.meta { font-size: 12px; color: #555; }
table.m td { cursor: pointer; }
table.m td.sel { outline: 2px solid #246; outline-offset: 1px; }
.detail { display: flex; flex-wrap: wrap; gap: 1.2em; margin-top: .6em; }
.panel h3 { font-size: 13px; margin: 0 0 .2em; font-weight: 600; }
.panel { min-width: 300px; }
svg text { font: 11px system-ui, sans-serif; fill: #444; }
table.h { border-collapse: collapse; font-size: 12px; }
table.h td, table.h th { padding: 2px 8px; border-bottom: 1px solid #eee; text-align: left; }
.raise { color: #b00; } .clear { color: #070; }
</style>
</head>
<body>
<h1>mpmwatch: model–plant mismatch monitor</h1>
<div class="sub">Each cell: norm of MI between the dither (column) and the residual of the CV (row), in bits, and the
element's p-value. Under the default rule an element is significant when its p-value is at most alpha: one test over
every lag of MI, joint-lag MI and the cross-correlation; the cell names the statistic and lag that decided.
Grey: no evidence of mismatch; orange to red: significant. A red frame: alarm raised.
Refreshes every 3 s. <span id="stamp"></span></div>
<div id="root">loading…</div>
<script>
function colour(ratio, sig) {
  if (!sig) { const g = Math.round(235 - 40 * Math.min(ratio, 1)); return `rgb(${g},${g},${g})`; }
  const t = Math.min((ratio - 1) / 3, 1);
  return `rgb(255,${Math.round(190 - 150 * t)},${Math.round(90 - 80 * t)})`;
}
const sel = {};
// A line/bar chart as inline SVG. xs: numbers; series: [{ys, kind: 'bar'|'line'|'dots', colour, dash, label}].
function chart(xs, series, opt) {
  const W = opt.w || 360, H = opt.h || 170, L = 48, R = 10, T = 10, B = 30;
  const all = series.flatMap(s => s.ys).filter(v => Number.isFinite(v));
  let lo = opt.ymin != null ? opt.ymin : Math.min(0, ...all), hi = opt.ymax != null ? opt.ymax : Math.max(...all, lo + 1e-12);
  if (hi <= lo) hi = lo + 1;
  hi += (hi - lo) * 0.05;
  const pad = (Math.max(...xs) - Math.min(...xs) || 1) / Math.max(xs.length, 2) * 0.7;
  const x0 = Math.min(...xs) - pad, x1 = Math.max(...xs, x0 + 1) + pad;
  const px = x => L + (x - x0) / (x1 - x0) * (W - L - R), py = y => T + (hi - y) / (hi - lo) * (H - T - B);
  let g = `<svg width="${W}" height="${H}" role="img" aria-label="${esc(opt.title || '')}">`;
  g += `<line x1="${L}" y1="${py(lo)}" x2="${W - R}" y2="${py(lo)}" stroke="#999"/><line x1="${L}" y1="${T}" x2="${L}" y2="${H - B}" stroke="#999"/>`;
  for (let k = 0; k <= 4; k++) {
    const y = lo + (hi - lo) * k / 4;
    g += `<text x="${L - 4}" y="${py(y) + 4}" text-anchor="end">${opt.fmt ? opt.fmt(y) : y.toPrecision(2)}</text>`;
    g += `<line x1="${L}" y1="${py(y)}" x2="${W - R}" y2="${py(y)}" stroke="#eee"/>`;
  }
  const step = Math.max(1, Math.ceil(xs.length / (opt.ticks || 8)));
  xs.forEach((x, k) => { if (k % step === 0) g += `<text x="${px(x)}" y="${H - B + 14}" text-anchor="middle">${opt.xfmt ? opt.xfmt(x, k) : x}</text>`; });
  g += `<text x="${(L + W - R) / 2}" y="${H - 2}" text-anchor="middle">${esc(opt.xlabel || '')}</text>`;
  const bw = Math.max(2, (W - L - R) / xs.length * 0.6);
  for (const s of series) {
    if (s.kind === 'bar') {
      s.ys.forEach((y, k) => { const a = py(Math.max(y, lo)), b = py(Math.max(Math.min(0, hi), lo));
        g += `<rect x="${px(xs[k]) - bw / 2}" y="${Math.min(a, b)}" width="${bw}" height="${Math.abs(b - a)}" fill="${s.colour}"><title>${esc(s.label)}: ${y.toPrecision(3)}</title></rect>`; });
    } else if (s.kind === 'dots') {
      s.ys.forEach((y, k) => { g += `<circle cx="${px(xs[k])}" cy="${py(y)}" r="3" fill="${(s.colours || [])[k] || s.colour}"><title>${esc(s.label)}: ${y.toPrecision(3)}</title></circle>`; });
    } else {
      const pts = s.ys.map((y, k) => `${px(xs[k])},${py(y)}`).join(' ');
      g += `<polyline points="${pts}" fill="none" stroke="${s.colour}" stroke-width="1.5"${s.dash ? ' stroke-dasharray="4 3"' : ''}/>`;
    }
  }
  const legend = series.filter(s => s.label).map((s, k) => `<tspan fill="${s.colour}" x="${W - R - 4}" dy="${k ? 13 : 0}">${s.kind === 'line' && s.dash ? '- -' : '■'} ${esc(s.label)}</tspan>`).join('');
  return g + `<text x="${W - R - 4}" y="${T + 10}" text-anchor="end" style="paint-order: stroke; stroke: #fafafa; stroke-width: 3px">${legend}</text></svg>`;
}
async function detail(c, m) {
  const ch = m.channels.find(x => x.dither === sel[c.id].dither && x.cv === sel[c.id].cv);
  if (!ch) return '';
  const q = `mv=${encodeURIComponent(ch.dither)}&cv=${encodeURIComponent(ch.cv)}`;
  const base = `api/v1/controllers/${encodeURIComponent(c.id)}`;
  const [pr, tr, al] = await Promise.all([fetch(`${base}/profile?${q}`), fetch(`${base}/trend?${q}`), fetch(`${base}/alarms?limit=20`)]);
  let h = `<div class="detail">`;
  if (pr.ok) {
    const p = await pr.json();
    const mi = [{ys: p.mi_bits, kind: 'bar', colour: '#5a8fc8', label: 'MI, bits'}, {ys: p.critical_bits, kind: 'line', colour: '#c33', dash: true, label: 'critical value'}];
    if (p.joint_bits) mi.push({ys: p.joint_bits, kind: 'line', colour: '#e9a23b', label: 'joint-lag MI'});
    h += `<div class="panel"><h3>${esc(ch.dither)} → e(${esc(ch.cv)}): MI against lag</h3>` + chart(p.lags, mi, {xlabel: 'lag (samples)', title: 'MI against lag', ymin: 0}) + '</div>';
    const lim = p.ccf_critical || p.lags.map(() => p.ccf_limit);
    h += `<div class="panel"><h3>cross-correlation against lag</h3>` + chart(p.lags, [
      {ys: p.ccf, kind: 'bar', colour: '#7b9e5a', label: 'r'},
      {ys: lim, kind: 'line', colour: '#c33', dash: true, label: p.ccf_critical ? '± critical |r| (family)' : '± limit'},
      {ys: lim.map(v => -v), kind: 'line', colour: '#c33', dash: true}], {xlabel: 'lag (samples)', title: 'CCF against lag'}) + '</div>';
  }
  if (tr.ok) {
    const t = await tr.json();
    if (t.points.length) {
      const xs = t.points.map((_, k) => k);
      const ys = t.points.map(pt => -Math.log10(Math.max(pt.p_value, 1e-300)));
      const series = [{ys, kind: 'dots', colour: '#888', colours: t.points.map(pt => pt.significant ? '#c33' : '#888'), label: '−log10 p per run'}];
      if (t.alpha) series.push({ys: xs.map(() => -Math.log10(t.alpha)), kind: 'line', colour: '#c33', dash: true, label: `alpha = ${t.alpha}`});
      const times = t.points.map(pt => pt.time.slice(11, 19));
      h += `<div class="panel"><h3>trend: last ${t.points.length} runs</h3>` + chart(xs, series, {xlabel: 'run time (UTC)', title: 'p-value trend', ymin: 0, ticks: 4, xfmt: (x, k) => times[k]}) + '</div>';
    }
  }
  if (al.ok) {
    const a = await al.json();
    const rows = a.history.slice().reverse().map(e => `<tr><td class="${e.event}">${esc(e.event)}</td><td>${esc(e.channel)}</td><td>${esc(e.time)}</td><td>${e.p_value != null ? e.p_value.toExponential(1) : ''}</td></tr>`).join('');
    h += `<div class="panel"><h3>alarm history (newest first)</h3>` + (rows ? `<table class="h"><tr><th>event</th><th>channel</th><th>time</th><th>p</th></tr>${rows}</table>` : '<p class="meta">no alarm raised or cleared yet</p>') + '</div>';
  }
  return h + '</div>';
}
function pick(id, dither, cv) { sel[id] = {dither, cv}; refresh(); }
function esc(s) { return String(s).replace(/[&<>"]/g, c => ({'&':'&amp;','<':'&lt;','>':'&gt;','"':'&quot;'}[c])); }
async function refresh() {
  try {
    const ctls = await (await fetch('api/v1/controllers')).json();
    let html = '';
    for (const c of ctls) {
      const r = await fetch(`api/v1/controllers/${encodeURIComponent(c.id)}/matrix`);
      const m = r.ok ? await r.json() : null;
      const alarms = new Set(c.active_alarms);
      html += `<div class="ctl"><h2>${esc(c.id)} ` +
        (c.active_alarms.length ? `<span class="bad">ALARM: ${c.active_alarms.map(esc).join(', ')}</span>` : '<span class="ok">no alarm</span>') +
        `</h2><div class="meta">window ${c.window_len}/${c.window_capacity} rows (${c.window_contiguous} contiguous), ` +
        `${c.ingested} samples in, dropped: ${Object.entries(c.dropped).filter(e => e[1] > 0).map(e => e[0] + ' ' + e[1]).join(', ') || 'none'}</div>`;
      if (!m) { html += '<p>no analysis yet</p></div>'; continue; }
      if (m.status !== 'ok') { html += `<p>last run (${esc(m.time)}): ${esc(m.status)} — ${esc(m.message || '')}</p></div>`; continue; }
      if (!sel[c.id] || !m.channels.some(x => x.dither === sel[c.id].dither && x.cv === sel[c.id].cv)) {
        const first = m.channels.find(x => alarms.has(`${x.dither}→${x.cv}`)) || m.channels.find(x => x.significant) || m.channels[0];
        if (first) sel[c.id] = {dither: first.dither, cv: first.cv};
      }
      html += '<table class="m"><tr><th></th>' + m.dither.map(d => `<th>${esc(d)}</th>`).join('') + '</tr>';
      m.cv.forEach((cv, j) => {
        html += `<tr><th>e(${esc(cv)})</th>`;
        m.dither.forEach((d, i) => {
          const ch = m.channels.find(x => x.mv_index === i && x.cv_index === j);
          if (!ch) { html += '<td title="dither not excited">–</td>'; return; }
          const ratio = ch.statistic_critical_bits > 0 ? ch.statistic_bits / ch.statistic_critical_bits : 0;
          const classes = [alarms.has(`${d}→${cv}`) ? 'alarm' : '', sel[c.id] && sel[c.id].dither === d && sel[c.id].cv === cv ? 'sel' : ''].join(' ').trim();
          const click = `pick(${esc(JSON.stringify(c.id))}, ${esc(JSON.stringify(d))}, ${esc(JSON.stringify(cv))})`;
          html += `<td class="${classes}" onclick="${click}" style="background:${colour(ratio, ch.significant)}" title="${esc(ch.reason)}">` +
            `${ch.norm_bits.toFixed(4)}<br><small>p = ${ch.p_value.toExponential(1)}</small><br><small>${esc(ch.verdict)}` +
            (ch.significant ? ` (${esc(ch.statistic)}${ch.peak_lag != null ? ', lag ' + ch.peak_lag : ''})` : '') +
            '</small></td>';
        });
        html += '</tr>';
      });
      html += `</table><div class="meta">run ${esc(m.time)}, ${m.n} samples, up to ${m.surrogates} surrogates, ` +
        (m.method === 'paper' ? `paper's rule, z = ${m.sigma}, ` : `alpha = ${m.alpha} per element, `) +
        `${m.duration_s.toFixed(2)} s. Click a cell for its profile, trend and history.</div>` + await detail(c, m) + '</div>';
    }
    document.getElementById('root').innerHTML = html || 'no controllers configured';
    document.getElementById('stamp').textContent = 'Updated ' + new Date().toLocaleTimeString() + '.';
  } catch (e) {
    document.getElementById('stamp').textContent = 'Update failed: ' + e;
  }
}
refresh();
setInterval(refresh, 3000);
</script>
</body>
</html>
"##;
