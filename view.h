// What the browser view shows (the page is view/view.html and
// view/view.js, compiled in): the run's state as JSON, the shaded mesh as
// a binary snapshot, the live page, and view.html, the page with the final
// state and mesh embedded that a run leaves beside result.gltf.
#ifndef RADIOSITY_VIEW_H
#define RADIOSITY_VIEW_H

#include <functional>
#include <string>
#include <vector>

#include "files.h"
#include "image.h"
#include "results.h"
#include "scene.h"

// What stays the same for the whole run.
struct ViewInfo {
  std::string scene;     // the scene's file name, shown as the title
  Camera camera;         // the pictures' camera: where the walk starts
  int width = 512, height = 512;  // the pictures' size (the camera's aspect)
  double epsilon = 1e-3;  // the run's target, drawn on the chart
};

// Where the run stands: the rows of log.csv so far and what is not in them.
struct ViewState {
  std::string status = "running";  // else how it ended ("converged", ...)
  int workers = 0;                 // alive at the last row
  long snapshot = 0;               // which mesh snapshot is served (0: none yet)
  long snapshot_shots = 0;         // the shot count it was taken at
};

// The state as JSON, with `rows`, the rows of log.csv from row `first` on
// (the page asks only for those it has not seen). Numbers as log.csv prints them, NaN as null:
// {"scene": .., "status": .., "workers": .., "epsilon": ..,
//  "camera": {"eye": [x,y,z], "target": [..], "fov": .., "width": .., "height": ..},
//  "snapshot": {"id": .., "shots": ..}, "first": .., "rows": [[seconds, shots,
//  wave, elements, unshot, rms, rel_rms], ..]}
std::string ViewStateJson(const ViewInfo& info, const ViewState& state,
                          const std::vector<LogRow>& rows, size_t first);

// The mesh snapshot the page draws, little-endian (coding.h):
//   "RVW1", u32 vertices n, u32 triangles m, f32 exposure (AutoExposure),
//   f64 x 3 origin, f32 x 3n positions less the origin, f32 x 3n linear
//   radiosity per vertex (negative and NaN as 0), u32 x 3m vertex ids
//   (quads split as in result.gltf).
// Float: WebGL draws in float; positions are taken relative to the middle
// of the scene's box (in double) so that a scene far from its origin keeps
// its detail.
std::string ViewMeshBlob(const ShadedMesh& mesh, float exposure);
// The same handed to `put` about a megabyte at a time (view.html of 10^6
// elements is never held whole); false when `put` failed.
bool ViewMeshBlob(const ShadedMesh& mesh, float exposure, const FileSink& put);

// The live page (view.html with view.js in it): it asks the server for
// state.json and mesh.bin.
std::string ViewPage();

// The same page with a state (ViewStateJson) and a mesh embedded, handed
// to `put` in pieces: one file that shows them from file://, needing
// nothing else. `mesh_blob` hands a ViewMeshBlob's bytes to its sink (in
// any pieces), which Base64-encodes them as they come. False when a write
// failed.
bool WriteOfflineViewPage(const std::string& state_json,
                          const std::function<bool(const FileSink&)>& mesh_blob,
                          const FileSink& put);

// Base64 (RFC 4648, padded) of `bytes`.
std::string Base64(const std::string& bytes);

#endif
