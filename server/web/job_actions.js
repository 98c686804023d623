// Jobs: their actions, shared by the list and the job's own view

import {api, jobPath} from './api.js';
import {FINISHED} from './contract.js';
import {h, setText} from './dom.js';
import {flash, reportError} from './page.js';

export function stateBadge(state) {
  return h('span', {class: `state ${state}`, text: state});
}

// Runs an action from a button: the button is disabled meanwhile; errors are flashed.
export async function act(button, what, work) {
  button.disabled = true;
  try {
    return await work();
  } catch (error) {
    reportError(what, error);
    return undefined;
  } finally {
    button.disabled = false;
  }
}

// The buttons for what can be done to `job` in its state. `applied(status)` gets the job's
// new status; `deleted()` is called once it is removed.
export function jobButtons(job, {applied, deleted}) {
  const buttons = [];
  const post = (label, verb, cls) => {
    const button = h('button', {
      type: 'button',
      class: cls,
      text: label,
      dataset: {action: verb},
      onclick: () =>
        act(button, `${label} ${job.name || job.id}`, async () =>
          applied(await api('POST', jobPath(job.id, `/${verb}`))),
        ),
    });
    buttons.push(button);
  };
  // What cannot be undone takes two clicks: the first arms it for a few seconds.
  const twoClicks = (label, question, verb, then) => {
    let armed = 0;
    const button = h('button', {
      type: 'button',
      class: 'danger',
      text: label,
      dataset: {action: verb},
      onclick: () => {
        if (!armed) {
          setText(button, question);
          armed = setTimeout(() => {
            armed = 0;
            setText(button, label);
          }, 4000);
          return;
        }
        clearTimeout(armed);
        armed = 0;
        act(button, `${label} ${job.name || job.id}`, then);
      },
    });
    buttons.push(button);
  };
  if (job.state === 'running' || job.state === 'queued') post('Pause', 'pause');
  if (job.state === 'paused') post('Resume', 'resume');
  // A canceled job is retried too: it renders what it lacked, under the same id.
  if (job.state === 'failed' || job.state === 'canceled') post('Retry', 'retry');
  if (!FINISHED.has(job.state)) {
    twoClicks('Cancel', 'Really cancel?', 'cancel', async () =>
      applied(await api('POST', jobPath(job.id, '/cancel'))),
    );
  }
  if (FINISHED.has(job.state)) {
    twoClicks('Delete', 'Really delete?', 'delete', async () => {
      await api('DELETE', jobPath(job.id));
      deleted();
    });
  }
  return buttons;
}

// The priority's number input: a change is sent at once (PATCH /v1/jobs/{id}).
export function priorityInput(getJob, applied) {
  const input = h('input', {
    type: 'number',
    min: 0,
    max: 100,
    step: 1,
    class: 'priority',
    'aria-label': 'Priority',
    onchange: async () => {
      const job = getJob();
      const value = Number(input.value);
      if (!Number.isInteger(value) || value < 0 || value > 100) {
        flash('A priority is a whole number from 0 to 100.');
        input.value = job.priority;
        return;
      }
      if (value === job.priority) return;
      input.disabled = true;
      try {
        applied(await api('PATCH', jobPath(job.id), {priority: value}));
      } catch (error) {
        reportError(`Priority of ${job.name || job.id}`, error);
        input.value = getJob().priority;
      } finally {
        input.disabled = FINISHED.has(getJob().state);
      }
    },
  });
  return input;
}

export function syncPriority(input, job) {
  input.disabled = FINISHED.has(job.state);
  if (document.activeElement !== input) input.value = job.priority;
}
