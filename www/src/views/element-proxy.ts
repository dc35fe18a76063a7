// Stands in for a canvas element inside the render worker: the page forwards its pointer and wheel
// events here, and three.js's OrbitControls and the views listen to this as they would to the
// element (it is its own ownerDocument: the controls follow a drag on the document).

/** The event fields the views and OrbitControls read, copied by the page. */
export interface ForwardedEvent {
  type: string;
  pointerId: number;
  pointerType: string;
  button: number;
  buttons: number;
  /** Relative to the canvas, CSS pixels (the proxy's box starts at 0, 0). */
  clientX: number;
  clientY: number;
  deltaX: number;
  deltaY: number;
  deltaMode: number;
  ctrlKey: boolean;
  metaKey: boolean;
  shiftKey: boolean;
}

export class ElementProxy extends EventTarget {
  clientWidth = 1;
  clientHeight = 1;
  readonly style: Record<string, string> = {};
  readonly ownerDocument = this;

  getRootNode(): this {
    return this;
  }

  getBoundingClientRect(): { left: number; top: number; right: number; bottom: number; width: number; height: number; x: number; y: number } {
    const [width, height] = [this.clientWidth, this.clientHeight];
    return { left: 0, top: 0, right: width, bottom: height, width, height, x: 0, y: 0 };
  }

  // The page captures the pointer on the real canvas.
  setPointerCapture(): void {}
  releasePointerCapture(): void {}
  hasPointerCapture(): boolean {
    return false;
  }
  focus(): void {}

  /** Replays an event the page forwarded. */
  replay(forwarded: ForwardedEvent): void {
    const event = new Event(forwarded.type, { cancelable: true });
    const { type: _, ...fields } = forwarded;
    const all = { ...fields, pageX: fields.clientX, pageY: fields.clientY, offsetX: fields.clientX, offsetY: fields.clientY };
    // A plain Event has none of these: own properties, as a PointerEvent or WheelEvent would have.
    for (const [key, value] of Object.entries(all)) Object.defineProperty(event, key, { value });
    this.dispatchEvent(event);
  }
}
