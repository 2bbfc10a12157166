// What main does once the options are read: list the hosts, be a worker,
// or run a master from the scene to its outputs. An error ends the program
// at once with its exit status and one line on stderr.
#ifndef RADIOSITY_APP_H
#define RADIOSITY_APP_H

#include <cmath>
#include <functional>
#include <future>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "checkpoint.h"
#include "elemb.h"
#include "exit_status.h"
#include "files.h"
#include "image.h"
#include "mesh.h"
#include "options.h"
#include "progress.h"
#include "results.h"
#include "scene.h"
#include "scheduler.h"
#include "solver.h"
#include "subdivide.h"
#include "transport.h"
#include "view.h"
#include "viewserver.h"
#include "writers.h"

class WorkerPool;
struct Surface;

// A message as the terminal may show it: names from the command line and
// the scene can hold control characters and escape sequences, shown as \xNN.
std::string Printable(const std::string& text);

// --dump-hosts: the hosts of -H FILE as parsed, one a line on stdout.
ExitStatus DumpHosts(const Options& opts);

// --worker: the worker protocol on stdin/stdout, or on the connection to
// --connect HOST:PORT.
ExitStatus WorkerMain(const Options& opts);

class ThreadedPool;

// A master's run in the order main takes it.
class MasterRun {
 public:
  explicit MasterRun(const Options& opts);
  MasterRun(const MasterRun&) = delete;
  MasterRun& operator=(const MasterRun&) = delete;
  ~MasterRun();

  // Loads the scene, the camera and the reference; starts the workers,
  // which mesh the scene while the master does; checks the checkpoint to
  // resume and that the one to write can be; opens the output directory
  // and log.csv.
  void Build();
  // Solves until converged, stopped or out of shots or time.
  void Run();
  // Writes the results and prints the summary.
  void WriteOutputs();

 private:
  void CheckOutputs(const std::vector<Input>& ck_inputs);
  void StartWorkers();
  void MeshScene(std::vector<Surface> surfaces);
  void JoinWorkers();
  void Resume();
  void OnSample(const Sample& s);
  void Note(const std::string& line, bool warning);
  std::string FrameName(int wave) const;
  // Shades the solution `b` (per element) and finds its exposure here,
  // once, then draws and writes it to every path (and to hdr_path as
  // Radiance RGBE, if given) on a thread of writers_, after the picture
  // before it is written, while the run goes on. That thread reads the
  // mesh's points (lent to the shaded mesh): the mesh must not change
  // before Drawn().
  std::pair<std::shared_ptr<const ShadedMesh>, float> Picture(const ElemB& b,
                                                              const std::vector<std::string>& paths,
                                                              const std::string& hdr_path = "");
  // A wave's picture of `b` made wholly on a thread of writers_: shaded,
  // exposed and drawn there from a copy of b (24 bytes an element until it
  // is shaded), then written to every path, so that the workers compute
  // the next wave's columns while it is made. The mesh must not change
  // before Drawn().
  void PictureLater(const ElemB& b, const std::vector<std::string>& paths);
  // Both: on a thread of writers_, `shade` gives the shaded mesh and its
  // exposure; drawn from it (Drawn() waits for that), the mesh is let go
  // and the picture written to every path (and to hdr_path as Radiance
  // RGBE, if given).
  using Shading = std::function<std::pair<std::shared_ptr<const ShadedMesh>, float>()>;
  void StartDrawing(Shading shade, const std::vector<std::string>& paths,
                    const std::string& hdr_path);
  // Waits until the last picture is drawn (its files may still be being
  // encoded and written).
  void Drawn();
  // Waits for the pictures being drawn and written; dies if one failed.
  void PicturesDone();
  void SaveCheckpoint(const RunState& state);
  ViewInfo ViewOf() const;  // what the browser view shows of this run

  const Options& opts_;
  std::vector<Input> inputs_;  // what no output may replace
  Staging staging_;            // the outputs until they are all written
  Writers writers_;            // pictures being written into staging_
  std::shared_future<void> drawn_;  // ready once the last picture is drawn
  RunOptions run_;  // opts_.run with the run's hooks
  Scene scene_;
  Camera camera_;
  std::vector<glm::dvec3> ref_;  // empty without --reference
  Mesh mesh_;
  RunIdentity identity_;
  Checkpoint resume_;
  LogCsv log_;
  std::unique_ptr<Solver> solver_;
  std::unique_ptr<Progress> progress_;
  // Notes come from the pool thread too (workers that sources bring:
  // ssh hosts, connect-back), while this thread draws the progress line.
  std::mutex progress_mu_;
  std::unique_ptr<Subdivider> subdivider_;
  long built_ = 0;  // elements as built, before dividing
  std::unique_ptr<WorkerPool> starting_;  // StartWorkers' pool, until JoinWorkers
  long local_workers_ = 0;                 // forked by StartWorkers
  std::unique_ptr<Transport> transport_;
  ThreadedPool* pool_thread_ = nullptr;  // transport_, when the pool has its thread
  long sub_limit_ = 0;  // elements subdivision may reach: kMaxElements, or what memory allows
  RunResult result_;
  std::unique_ptr<ViewServer> view_;  // --view
  int workers_ = 0;                   // alive at the last sample
  double last_unshot_ = 1;            // the unshot fraction at the last sample
  double view_floor_ = HUGE_VAL;      // no view snapshot above this unshot fraction
};

#endif
