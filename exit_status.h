// The program's exit statuses, in one place for main, the worker and the
// forked child. Any change here must be duplicated in the man page
// (man/radiosity.1, EXIT STATUS); tests/manpage.sh checks that it is.
#ifndef RADIOSITY_EXIT_STATUS_H
#define RADIOSITY_EXIT_STATUS_H

enum ExitStatus {
  kExitOk = 0,          // done, or stopped on request
  kExitFailure = 1,     // run-time failure: did not converge, no worker, I/O error
  kExitUsage = 2,       // bad usage or bad input
  kExitExecFailed = 127,  // a forked worker whose exec failed (the shell's status)
};

#endif
