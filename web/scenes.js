// The scene generator's panel: a scenario made in the tab (scene-worker.js)
// opens like any sequence.
import { $, guarded, progress } from './state.js';
import { openGenerated } from './sequence.js';
import { sceneChoices } from './core.js';

// The scenario the panel offers first: the opening sample's.
const FIRST_SCENARIO = 'dynamic-pull';

// Makes a scene in the scene worker; `onProgress(written, total)`.
export function makeScene(options, onProgress) {
  return new Promise((resolve, reject) => {
    const w = new Worker('./scene-worker.js', { type: 'module' });
    w.onmessage = (e) => {
      if (e.data.progress) { onProgress(...e.data.progress); return; }
      w.terminate();
      if (e.data.ok) resolve(e.data); else reject(new Error(e.data.error));
    };
    w.onerror = (e) => { w.terminate(); reject(new Error(`scene worker: ${e.message}`)); };
    w.postMessage({ options });
  });
}

function fill(select, items) {
  for (const it of items) {
    const o = new Option(it.name, it.name);
    if (it.description) o.title = it.description;
    select.append(o);
  }
}

export function bindScenePanel() {
  const c = sceneChoices();
  fill($('scene-scenario'), c.scenarios);
  fill($('scene-variant'), [{ name: '' }, ...c.variants]);
  $('scene-variant').options[0].textContent = "the scenario's own";
  fill($('scene-colour'), [{ name: '' }, ...c.colours.map((name) => ({ name }))]);
  $('scene-colour').options[0].textContent = "the variant's";
  $('scene-scenario').value = FIRST_SCENARIO;
  $('scene-frames').max = String(c.max_frames);
  for (const id of ['scene-occluder', 'scene-pull']) $(id).max = String(c.max_scale);
  const shown = () => {
    $('scene-occluder-value').textContent = `${Number($('scene-occluder').value).toFixed(2)}x`;
    $('scene-pull-value').textContent = `${Number($('scene-pull').value).toFixed(2)}x`;
  };
  $('scene-occluder').oninput = shown;
  $('scene-pull').oninput = shown;
  shown();
  $('scene-make').onclick = guarded(async () => {
    const options = {
      scenario: $('scene-scenario').value,
      frames: Number($('scene-frames').value),
      seed: Number($('scene-seed').value),
      occluder_scale: Number($('scene-occluder').value),
      pull_scale: Number($('scene-pull').value),
    };
    if ($('scene-variant').value) options.variant = $('scene-variant').value;
    if ($('scene-colour').value) options.rope_colour = $('scene-colour').value;
    $('scene-make').disabled = true;
    try {
      const made = await makeScene(options, (done, total) => {
        progress(done, total);
        $('scene-status').textContent = `rendering frame ${done} of ${total}…`;
      });
      $('scene-status').textContent = '';
      await openGenerated(made.name, made.files);
    } finally {
      $('scene-make').disabled = false;
      $('scene-status').textContent = '';
      progress(null);
    }
  });
}
