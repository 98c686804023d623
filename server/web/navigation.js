// Moving to another view without loading the page again: the router (app.js) registers
// itself here, so that the views it shows can navigate without importing it.

let router = () => {};

export function setRouter(route) {
  router = route;
}

export function navigate(address) {
  history.pushState(null, '', address);
  router();
}
