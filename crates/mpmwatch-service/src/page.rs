//! The status page at `/`: every controller's MI matrix as a heat map (cell colour = statistic
//! over its critical value; a red frame while the channel's alarm is raised), refreshed every
//! few seconds from the JSON API. Plain HTML and CSS with one small script, no dependencies.

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
      html += '<table class="m"><tr><th></th>' + m.dither.map(d => `<th>${esc(d)}</th>`).join('') + '</tr>';
      m.cv.forEach((cv, j) => {
        html += `<tr><th>e(${esc(cv)})</th>`;
        m.dither.forEach((d, i) => {
          const ch = m.channels.find(x => x.mv_index === i && x.cv_index === j);
          if (!ch) { html += '<td title="dither not excited">–</td>'; return; }
          const ratio = ch.statistic_critical_bits > 0 ? ch.statistic_bits / ch.statistic_critical_bits : 0;
          const cls = alarms.has(`${d}→${cv}`) ? ' class="alarm"' : '';
          html += `<td${cls} style="background:${colour(ratio, ch.significant)}" title="${esc(ch.reason)}">` +
            `${ch.norm_bits.toFixed(4)}<br><small>p = ${ch.p_value.toExponential(1)}</small><br><small>${esc(ch.verdict)}` +
            (ch.significant ? ` (${esc(ch.statistic)}${ch.peak_lag != null ? ', lag ' + ch.peak_lag : ''})` : '') +
            '</small></td>';
        });
        html += '</tr>';
      });
      html += `</table><div class="meta">run ${esc(m.time)}, ${m.n} samples, up to ${m.surrogates} surrogates, ` +
        (m.method === 'paper' ? `paper's rule, z = ${m.sigma}, ` : `alpha = ${m.alpha} per element, `) +
        `${m.duration_s.toFixed(2)} s</div></div>`;
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
