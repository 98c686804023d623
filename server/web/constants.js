// The dashboard's pace and limits: how often it asks, how much it holds.

export const TOKEN_KEY = 'tessera.token';
export const PAGE_SIZE = 50;
export const MAX_ZOOM = 64; // screen pixels per image pixel at the most
export const POLL_MS = 3000; // how often a view reloads where the coordinator serves no events
export const DEFAULT_FPS = 24; // the flipbook's pace: the job's status does not carry the scene's fps
export const FRAMES_REFRESH_MS = 1000; // GET /frames at most this often while frames change ...
export const FRAMES_REFRESH_MAX_MS = 10000; // ... and up to this for long animations (1 ms a frame)
export const FRAME_IMAGE_FETCHES = 2; // frame images fetched at once for the strip and the flipbook
export const FRAME_IMAGE_RETRY_MS = 3000; // before a frame image that could not be fetched is asked for again
export const FRAME_IMAGE_ATTEMPTS = 3; // tries at a frame image before it waits to be asked for again
export const MAX_STRIP_FRAMES = 100000; // a frame list longer than this waits for GET /frames
