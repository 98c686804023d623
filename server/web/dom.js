// The DOM, without markup

// h('a', {href: '/x', class: 'c', 'data-nav': ''}, 'text', child...): an element. Keys with
// a dash are attributes; `on...` are listeners; the rest are properties. Strings become text
// nodes, so nothing passed here is ever parsed as HTML.
export function h(tag, props = {}, ...children) {
  const element = document.createElement(tag);
  for (const [key, value] of Object.entries(props)) {
    if (value === undefined || value === null || value === false) continue;
    if (key === 'class') element.className = value;
    else if (key === 'text') element.textContent = value;
    else if (key === 'dataset') Object.assign(element.dataset, value);
    else if (key.startsWith('on') && typeof value === 'function')
      element.addEventListener(key.slice(2), value);
    else if (key.includes('-')) element.setAttribute(key, value === true ? '' : String(value));
    else if (key === 'innerHTML' || key === 'outerHTML') throw new Error('no markup from data');
    else element[key] = value;
  }
  append(element, children);
  return element;
}

export function append(parent, children) {
  for (const child of children.flat(Infinity)) {
    if (child === null || child === undefined || child === false) continue;
    parent.append(child instanceof Node ? child : document.createTextNode(String(child)));
  }
  return parent;
}

// The element's children replaced by `children` (as h() takes them).
export function fill(element, ...children) {
  element.replaceChildren();
  return append(element, children);
}

export function setText(element, text) {
  const value = String(text);
  if (element.textContent !== value) element.textContent = value;
}

export const $ = (selector) => document.querySelector(selector);
