// The scene generator's panel and the page's opening look: a scenario made
// in the tab (scene-worker.js) opens like any sequence. The default page
// plays a bundled sample in a loop and meanwhile makes a longer version of
// it, which it switches to once ready.
import { state, $, guarded, progress } from './state.js';
import { openGenerated } from './sequence.js';
import { sceneChoices } from './core.js';

// The opening look: this scenario, made with these settings.
export const LONG_LOOK = { scenario: 'dynamic-pull', frames: 150, seed: 2 };

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
  fill($('scene-variant'), c.variants);
  fill($('scene-colour'), [{ name: '' }, ...c.colours.map((name) => ({ name }))]);
  $('scene-colour').options[0].textContent = "the variant's";
  $('scene-scenario').value = LONG_LOOK.scenario;
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
      variant: $('scene-variant').value,
      frames: Number($('scene-frames').value),
      seed: Number($('scene-seed').value),
      occluder_scale: Number($('scene-occluder').value),
      pull_scale: Number($('scene-pull').value),
    };
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

// Makes the opening look's long version and switches to it if the page is
// still on the sample it started with; `play` restarts playback.
export async function makeLongLook(startedOn, play) {
  const t0 = performance.now();
  const made = await makeScene(LONG_LOOK, (done, total) => { $('seq-details').textContent = `Making a longer scene in this tab: ${done} of ${total} frames…`; });
  state.longLook = { ms: performance.now() - t0 };
  $('seq-details').textContent = '';
  if (!state.seq || state.seq.name !== startedOn || state.explain) return;
  const playing = state.playing;
  state.playing = false;
  await state.busy;
  await openGenerated(made.name, made.files);
  if (playing) play();
}
