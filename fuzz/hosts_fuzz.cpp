// libFuzzer target: the hosts file parser (hosts.h). Besides not crashing,
// what it accepts must survive --dump-hosts: every host, printed by
// FormatHost in the file's own grammar, parses back to the same host.
#include <cstdint>
#include <cstdlib>
#include <string>
#include <vector>

#include "hosts.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  std::vector<HostSpec> hosts;
  std::string err;
  if (!ParseHosts(text, "fuzz", &hosts, &err)) {
    if (err.compare(0, 5, "fuzz:") != 0) std::abort();  // FILE:LINE: what
    return 0;
  }
  for (const HostSpec& h : hosts) {
    if (h.slots < 1 || h.slots > kMaxSlots || h.port < 0 || h.port > 65535) std::abort();
    std::vector<HostSpec> again;
    if (!ParseHosts(FormatHost(h) + "\n", "again", &again, &err) || again.size() != 1)
      std::abort();
    const HostSpec& g = again[0];
    if (g.user != h.user || g.name != h.name || g.port != h.port || g.slots != h.slots ||
        g.cmd != h.cmd)
      std::abort();
  }
  return 0;
}
