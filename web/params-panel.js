// The parameter panel, built from the core's list of every algorithm's
// parameters (parameterSchema: path, symbol, meaning, range, unit), and the
// settings as a shareable link. The core checks every value (parseParams).
import { $ } from './state.js';
import { parameterSchema, defaultParams } from './core.js';

const GROUP_TITLES = {
  shared: 'Every algorithm', upetrack: 'UPETrack', cpd: 'CPD', trackdlo: 'TrackDLO', cdcpd2: 'CDCPD2',
};

let schema = [];

// A value at `path` ('name' or 'section.name') of a parameter object.
export function getPath(params, path) {
  const [a, b] = path.split('.');
  return b === undefined ? params[a] : params[a][b];
}

function setPath(params, path, value) {
  const [a, b] = path.split('.');
  if (b === undefined) params[a] = value; else params[a] = { ...params[a], [b]: value };
}

// `r_vis` as r<sub>vis</sub>, built from text nodes (no HTML parsing).
function symbolNode(symbol) {
  const span = document.createElement('span');
  span.className = 'sym';
  const [base, sub] = symbol.split(/_(.+)/);
  span.append(base);
  if (sub) { const s = document.createElement('sub'); s.textContent = sub; span.append(s); }
  return span;
}

function rangeText(p) {
  const unit = p.unit ? ` ${p.unit}` : '';
  if (p.kind === 'number' || p.kind === 'integer') return `${p.min} to ${p.max}${unit}`;
  if (p.kind === 'choice') return p.choices.join(' | ');
  return 'on / off';
}

function input(p) {
  let el;
  if (p.kind === 'bool') {
    el = document.createElement('input');
    el.type = 'checkbox';
  } else if (p.kind === 'choice') {
    el = document.createElement('select');
    for (const c of p.choices) el.append(new Option(c, c));
  } else {
    el = document.createElement('input');
    el.type = 'number';
    el.min = String(p.min);
    el.max = String(p.max);
    el.step = p.kind === 'integer' ? '1' : String(p.step);
  }
  el.id = `p-${p.path}`;
  return el;
}

// Builds the panel into #params: one collapsible section per group.
export function buildParamPanel() {
  schema = parameterSchema();
  const form = $('params');
  form.textContent = '';
  for (const group of Object.keys(GROUP_TITLES)) {
    const section = document.createElement('details');
    section.className = 'param-group';
    section.dataset.group = group;
    const summary = document.createElement('summary');
    summary.textContent = GROUP_TITLES[group];
    section.append(summary);
    for (const p of schema.filter((x) => x.group === group)) {
      const row = document.createElement('label');
      row.className = 'param';
      row.title = `${p.meaning}. Range ${rangeText(p)}. In a parameter file: ${p.path}`;
      const unit = document.createElement('span');
      unit.textContent = p.unit;
      row.append(symbolNode(p.symbol), input(p), unit);
      const hint = document.createElement('span');
      hint.className = 'param-hint';
      hint.textContent = `${p.meaning} (${rangeText(p)})`;
      row.append(hint);
      section.append(row);
    }
    form.append(section);
  }
}

// Opens the sections of the algorithms in use (and the shared one).
export function showGroupsFor(algorithms) {
  for (const d of document.querySelectorAll('#params details.param-group')) {
    d.open = d.dataset.group === 'shared' || algorithms.includes(d.dataset.group);
  }
}

// Shown value of parameter p from its stored value, and back.
const shown = (p, v) => (p.scale === 1 ? v : Math.round(v * p.scale * 1e6) / 1e6);

export function setParamInputs(params) {
  for (const p of schema) {
    const el = $(`p-${p.path}`);
    const v = getPath(params, p.path);
    if (p.kind === 'bool') el.checked = v;
    else if (p.kind === 'choice') el.value = v;
    else el.value = String(shown(p, v));
  }
}

// The parameters typed in the panel, over `base` (not yet checked).
export function paramsFromInputs(base) {
  const next = structuredClone(base);
  for (const p of schema) {
    const el = $(`p-${p.path}`);
    let v;
    if (p.kind === 'bool') v = el.checked;
    else if (p.kind === 'choice') v = el.value;
    else v = Number(el.value) / p.scale;
    setPath(next, p.path, v);
  }
  return next;
}

// `p.<path>=<value>` for every parameter that differs from its default.
export function paramsQuery(params) {
  const defaults = defaultParams();
  const out = [];
  for (const p of schema) {
    const v = getPath(params, p.path);
    if (v !== getPath(defaults, p.path)) out.push([`p.${p.path}`, String(v)]);
  }
  return out;
}

// Applies the query's `p.<path>=<value>` to `params`; returns the problems.
export function applyParamsQuery(query, params) {
  const problems = [];
  const byPath = new Map(schema.map((p) => [p.path, p]));
  for (const [k, text] of query) {
    if (!k.startsWith('p.')) continue;
    const p = byPath.get(k.slice(2));
    if (!p) { problems.push(`${k}: no such parameter`); continue; }
    let v;
    if (p.kind === 'bool') v = text === 'true' ? true : text === 'false' ? false : null;
    else if (p.kind === 'choice') v = p.choices.includes(text) ? text : null;
    else v = text.trim() !== '' && Number.isFinite(Number(text)) ? Number(text) : null;
    if (v === null) problems.push(`${k}=${text} is not a ${p.kind === 'bool' ? 'true/false' : p.kind === 'choice' ? p.choices.join('/') : 'numeric'} value`);
    else setPath(params, p.path, v);
  }
  return problems;
}
