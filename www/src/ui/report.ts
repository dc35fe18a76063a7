// The mesh report as readable tables (built with DOM calls: file names never become markup).

import type { MeshReport, Vec3 } from "../core";
import { el } from "./dom";

const integer = new Intl.NumberFormat("en-US");
const decimal = new Intl.NumberFormat("en-US", { maximumFractionDigits: 3 });


function point(p: Vec3): string {
  return `(${p.map((c) => decimal.format(c)).join(", ")})`;
}

function loops(report: MeshReport): string {
  const [outer, ...holes] = report.loop_vertex_counts;
  if (outer === undefined) return "none";
  const parts = [`outer ${integer.format(outer)} vertices`];
  if (holes.length > 0) parts.push(`${holes.length === 1 ? "hole" : "holes"} ${holes.map((n) => integer.format(n)).join(", ")}`);
  return `${report.boundary_loops} (${parts.join("; ")})`;
}

type Row = [label: string, value: string, note?: string | undefined];

/** `planned`: this is the surface the planner works on (notes about planning apply to it). */
function rows(report: MeshReport, planned: boolean): Row[] {
  const [min, max] = report.bbox;
  const size: Vec3 = [max[0] - min[0], max[1] - min[1], max[2] - min[2]];
  const list: Row[] = [
    ["Vertices", integer.format(report.vertices)],
    ["Faces", integer.format(report.faces)],
    ["Edges", integer.format(report.edges)],
    ["Components", integer.format(report.components), planned && report.components > 1 ? "the largest is planned" : undefined],
    ["Boundary loops", loops(report)],
    ["Euler characteristic", integer.format(report.euler_characteristic)],
    ["Genus", integer.format(report.genus), handleNote(report)],
    ["Closed", report.closed ? "yes (a solid)" : "no"],
    ["Degenerate faces dropped", integer.format(report.degenerate_faces_dropped)],
    ["Duplicate faces dropped", integer.format(report.duplicate_faces_dropped)],
    ["Faces re-oriented", integer.format(report.faces_reoriented)],
    ["Pinch vertices split", integer.format(report.pinch_vertices_split)],
    ["Faces in other components", integer.format(report.faces_in_other_components)],
    ["Bounding box", `${point(min)} – ${point(max)} mm`],
    ["Size", `${size.map((c) => decimal.format(c)).join(" × ")} mm`],
    ["Area", `${decimal.format(report.area_mm2)} mm²`],
  ];
  return list;
}

function table(report: MeshReport, planned: boolean, caption: string, testId: string): HTMLTableElement {
  const t = el("table", { className: "report-table" });
  t.dataset["testid"] = testId;
  t.append(el("caption", { text: caption }));
  const body = el("tbody");
  for (const [label, value, note] of rows(report, planned)) {
    const tr = el("tr");
    tr.append(el("th", { text: label }));
    const td = el("td", { text: value });
    if (note !== undefined) td.append(el("span", { text: note, className: "note" }));
    tr.append(td);
    body.append(tr);
  }
  t.append(body);
  return t;
}

/** Replaces the container's content with the report of `name`. */
export function renderReport(container: HTMLElement, report: MeshReport, name: string): void {
  const closed = report.machined !== undefined;
  const parts: HTMLElement[] = [table(report, !closed, `Whole model — ${name}`, "report-model")];
  if (report.machined !== undefined) {
    const intro = el("p", { text: "A closed solid: the surface to machine is its top, the faces within the wall angle of the tool axis. Steep walls of bosses and pockets become holes.", className: "explain" });
    parts.push(intro, table(report.machined, true, "Machined top surface", "report-machined"));
  }
  container.replaceChildren(...parts);
}

/** What the planner did about handles: the cuts' count and lengths (genus > 0 only). */
function handleNote(report: MeshReport): string | undefined {
  const cuts = report.handle_cuts ?? [];
  if (report.genus <= 0 || cuts.length === 0) return undefined;
  const mm = cuts.map((c) => c.length_mm.toFixed(1)).join(", ");
  return `cut along ${cuts.length} handle loop${cuts.length === 1 ? "" : "s"} (${mm} mm): the path runs along both sides`;
}
