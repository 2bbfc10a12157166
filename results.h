// What a run leaves behind: result.csv, log.csv, the reference it is
// measured against (paper §5.2), and the shaded mesh pictures are made of.
#ifndef RADIOSITY_RESULTS_H
#define RADIOSITY_RESULTS_H

#include <cstdio>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "elemb.h"
#include "image.h"
#include "scheduler.h"
#include "mesh.h"
#include "scene.h"

// Per scene face: the area-weighted mean radiosity of the leaf elements
// over it (on a joined surface, each leaf weighted by its exact overlap
// with the face), negative rounding residue clamped to 0.
std::vector<glm::dvec3> FaceRadiosity(const Mesh& mesh, const ElemB& elem_b);

// result.csv: `face,object,area,B_r,B_g,B_b`, one row per accepted face.
bool WriteResultCsv(const std::string& path, const Scene& scene,
                    const std::vector<glm::dvec3>& face_b, std::string* err);

// A converged result.csv of the same scene, indexed like Scene::faces.
// Fails with "FILE:LINE: what" when it does not match the scene.
bool ReadReference(const std::string& path, const Scene& scene,
                   std::vector<glm::dvec3>* ref, std::string* err);

// RMS error over faces (area-weighted, channels averaged) and the same
// divided by the reference's area-weighted mean radiosity.
void RmsError(const Scene& scene, const std::vector<glm::dvec3>& face_b,
              const std::vector<glm::dvec3>& ref, double* rms, double* rel_rms);

// The same RMS error measured per point instead of per face, so that it
// sees how well the mesh follows shadows and light edges (a face's mean
// does not depend on how its elements are cut): at the centroid of every
// leaf of `ref` (a finer converged solution of the same scene and patch
// size), the radiosity as drawn (Shade, interpolated over the leaf's
// triangles as Render does) against the reference as drawn, weighted by
// the leaf's area.
void FieldError(const Mesh& mesh, const ElemB& elem_b, const Mesh& ref,
                const ElemB& ref_b, double* rms, double* rel_rms);

// One row of log.csv; rms and rel_rms are NaN without a reference.
struct LogRow {
  double seconds;
  long shots;
  int wave;
  long elements;
  double unshot, rms, rel_rms;
};

// log.csv, a row per progress sample. The rows are kept as written, for
// a checkpoint and for the error chart drawn at the end (error.svg).
class LogCsv {
 public:
  ~LogCsv();
  bool Open(const std::string& path, std::string* err);
  void Row(const Sample& s, const double* rms, const double* rel_rms);
  bool Close(std::string* err);
  // The rows written so far as text, without the header (for a
  // checkpoint); and those of an earlier part of the run, written as they
  // are (--resume).
  const std::string& text() const { return text_; }
  void Restore(const std::string& text);
  // The rows written so far, read back from text().
  std::vector<LogRow> rows() const;

 private:
  std::FILE* f_ = nullptr;
  std::string path_;
  std::string text_;
};

// Leaf elements with radiosity averaged to their vertices (inside one face;
// faces do not share vertices), ready to draw or export.
ShadedMesh Shade(const Mesh& mesh, const ElemB& elem_b);

#endif
