// The page's STEP state: the file's faces (3D view and face list), the faces selected for
// machining (toggled by a click in the 3D view or in the list; `faces=` in the URL when not all),
// and which of them the part's own surface covers. The planner worker holds the file itself.

import type { StepFace, StepPart } from "./lib/index";
import { FaceList } from "./ui/face-list";
import type { Views } from "./views/views";

export class StepPage {
  private faces: StepFace[] | null = null;
  private selected = new Set<number>();
  /** The faces the shown part (the planned surface) is made of; null: no part of this file. */
  private partFaces: Set<number> | null = null;
  private hideSurface = false;

  /** Called after the user changed the selection. */
  onChange: () => void = () => {};

  constructor(
    private readonly views: Views,
    private readonly list: FaceList,
  ) {
    list.onChange = (ids) => this.select(ids);
    views.onFacePick = (index) => {
      const face = this.faces?.[index];
      if (face === undefined) return;
      const next = new Set(this.selected);
      if (!next.delete(face.id)) next.add(face.id);
      this.select([...next]);
    };
  }

  /** A STEP file was read: its faces, with `asked` selected (all when null; unknown ids dropped). */
  show(step: StepPart, asked: number[] | null): void {
    this.faces = step.faces;
    const ids = new Set(step.faces.map((f) => f.id));
    this.selected = new Set(asked === null ? ids : asked.filter((id) => ids.has(id)));
    this.partFaces = null;
    this.views.setFaces(step.drawing); // transfers its arrays
    this.list.show(step.faces, this.selected);
    this.update();
  }

  /** An STL part: no faces. */
  clear(): void {
    if (this.faces === null) return;
    this.faces = null;
    this.selected.clear();
    this.partFaces = null;
    this.views.setFaces(null);
    this.list.show(null, this.selected);
  }

  isStep(): boolean {
    return this.faces !== null;
  }

  /** The selected faces, in the file's order. */
  selection(): number[] {
    return (this.faces ?? []).filter((f) => this.selected.has(f.id)).map((f) => f.id);
  }

  /** All faces selected (the URL then leaves `faces` out). */
  allSelected(): boolean {
    return this.faces !== null && this.selected.size === this.faces.length;
  }

  /** Whether the shown part is made of the selected faces. */
  partIsSelection(): boolean {
    return this.partFaces !== null && this.partFaces.size === this.selected.size && [...this.selected].every((f) => this.partFaces!.has(f));
  }

  /** The part now shown is made of `faces` (null: none of this file is shown). */
  setPart(faces: number[] | null): void {
    this.partFaces = faces && new Set(faces);
    this.update();
  }

  /** Draw the part's surface (spiral, flank) or only the faces (Coons band: the path lies on them). */
  setSurfaceHidden(hidden: boolean): void {
    this.hideSurface = hidden;
    this.update();
  }

  private select(ids: number[]): void {
    this.selected = new Set(ids);
    this.list.set(this.selected);
    this.update();
    this.onChange();
  }

  private update(): void {
    if (this.faces === null) return;
    const n = this.faces.length;
    const selected = new Uint8Array(n);
    const covered = new Uint8Array(n);
    const surfaceShown = !this.hideSurface && this.partFaces !== null;
    this.faces.forEach((f, i) => {
      selected[i] = this.selected.has(f.id) ? 1 : 0;
      covered[i] = surfaceShown && this.partFaces!.has(f.id) ? 1 : 0;
    });
    this.views.setFaceState({ selected, covered, hideSurface: !surfaceShown });
  }
}

/** `faces=1,2,3` of a URL query, or null. */
export function facesFromQuery(search: string): number[] | null {
  const text = new URLSearchParams(search).get("faces");
  if (text === null) return null;
  const ids = text.split(",").map(Number);
  return ids.every((id) => Number.isInteger(id) && id > 0) ? ids : null;
}
