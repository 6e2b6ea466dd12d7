// The store: holds the state, applies actions through the reducer, and tells subscribers once per
// animation frame at most (a burst of 200 position events costs one render).
import { reduce } from './reducer';
import { initialState, type Action, type State } from './state';

export type Listener = (state: State, previous: State) => void;

export interface Scheduler {
  /** Runs fn soon, once; requestAnimationFrame in the page, a microtask in tests. */
  (fn: () => void): void;
}

export class Store {
  private state: State;
  private rendered: State;
  private readonly listeners = new Set<Listener>();
  private scheduled = false;

  constructor(
    private readonly schedule: Scheduler = (fn) => queueMicrotask(fn),
    initial: State = initialState(),
  ) {
    this.state = initial;
    this.rendered = initial;
  }

  getState(): State {
    return this.state;
  }

  dispatch(action: Action): void {
    const next = reduce(this.state, action);
    if (next === this.state) return;
    this.state = next;
    if (!this.scheduled && this.listeners.size > 0) {
      this.scheduled = true;
      this.schedule(() => this.flush());
    }
  }

  /** Calls every listener with the current state and the state they saw last time. */
  flush(): void {
    this.scheduled = false;
    const previous = this.rendered;
    this.rendered = this.state;
    if (previous === this.state) return;
    for (const l of this.listeners) l(this.state, previous);
  }

  subscribe(l: Listener): () => void {
    this.listeners.add(l);
    return () => this.listeners.delete(l);
  }
}
