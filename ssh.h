// Workers on remote hosts over ssh (libssh): the hosts of a hosts file
// that are not "localhost".
//
// Each host is set up on a thread of its own, so that a slow or dead host
// delays nobody: connect (~/.ssh/config read first, then the file's user
// and port), check the host key against known_hosts, authenticate (the
// ssh agent, then the default keys), copy this binary over unless the
// file gives cmd= (see Upload in ssh.cpp), then open one channel per slot
// running "BINARY --worker". The channels of a host share one ssh
// connection; a server whose MaxSessions is below the slots gets more
// connections. The ready channels are then handed to the pool's thread,
// where they are Conns with non-blocking I/O in its poll loop.
#ifndef RADIOSITY_SSH_H
#define RADIOSITY_SSH_H

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "hosts.h"
#include "pool.h"

struct SshOptions {
  // Record the key of a host not yet in known_hosts instead of refusing
  // it (a changed key is refused all the same).
  bool accept_new_host_keys = false;
  // Connecting, and each step of the setup, give up after this long.
  double timeout_s = 10;
};

// Starts setting up `hosts` (none of them local) at once. `note` gets, on
// the pool's thread, one line per host that could not be set up, as a
// warning ("HOST: what happened; skipped"), and progress lines for -v.
std::unique_ptr<WorkerSource> StartSshHosts(
    const std::vector<HostSpec>& hosts, const SshOptions& opts,
    std::function<void(const std::string&, bool warning)> note);

#endif
