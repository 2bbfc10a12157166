// radiosity: main. The options are options.cpp's, the run app.cpp's;
// everything else lives in the modules (see README.md, Layout).
#include <cstdio>
#include <string>

#include "app.h"
#include "exit_status.h"
#include "options.h"


int main(int argc, char** argv) {
  Options opts;
  std::string err;
  switch (ParseOptions(argc, argv, &opts, &err)) {
    case Parsed::kRun: break;
    case Parsed::kHelp: std::fputs(kUsage, stdout); return kExitOk;
    case Parsed::kVersion: std::printf("radiosity %s\n", kRadiosityVersion); return kExitOk;
    case Parsed::kDumpHosts: return DumpHosts(opts);
    case Parsed::kWorker: return WorkerMain(opts);
    case Parsed::kNoScene: std::fputs(kUsage, stderr); return kExitUsage;
    case Parsed::kError: std::fprintf(stderr, "radiosity: %s\n", Printable(err).c_str()); return kExitUsage;
  }
  MasterRun run(opts);
  run.Build();
  run.Run();
  run.WriteOutputs();
  return kExitOk;
}
