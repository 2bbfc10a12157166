// The hosts file (-H): which machines run workers, how many, and how.
//
// Grammar (the MPI hostfile's, plus cmd=; man/radiosity.1 HOSTS FILE):
//
//   file     = { line }
//   line     = [ host { blank key "=" value } ] [ "#" comment ] newline
//   host     = [ user "@" ] name [ ":" port ]
//   name     = hostname | IPv4 address | "[" IPv6 address "]"
//   key      = "slots" | "cmd"
//   slots    = 1 .. 256      workers on that host (default 1)
//   cmd      = PATH          the remote binary, run as "PATH --worker" by the
//                            login shell (default: upload this binary)
//   port     = 1 .. 65535    (default: ~/.ssh/config's, else 22)
//
// Blank lines and comments are ignored; a key may be given once per line.
// The name "localhost" forks workers on this machine without ssh (so it
// takes no user and no port: write 127.0.0.1 to reach this machine by ssh).
#ifndef RADIOSITY_HOSTS_H
#define RADIOSITY_HOSTS_H

#include <string>
#include <vector>

struct HostSpec {
  std::string user;  // empty: ~/.ssh/config's, else the local user
  std::string name;  // without the brackets of an IPv6 address
  int port = 0;      // 0: ~/.ssh/config's, else 22
  int slots = 1;
  std::string cmd;   // empty: upload this binary
  int line = 0;      // in the file, for messages

  bool Local() const { return name == "localhost"; }
  // As written in the file ("user@host:port"), for messages.
  std::string Label() const;
};

constexpr int kMaxSlots = 256;
// Slots of one hosts file in all: each is a worker process and a
// connection of the master's.
constexpr int kMaxTotalSlots = 4096;

// Parses the text of a hosts file; `file` names it in messages. False with
// *err = "FILE:LINE: what" at the first error.
bool ParseHosts(const std::string& text, const std::string& file, std::vector<HostSpec>* hosts,
                std::string* err);

// Reads and parses FILE; a file that lists no host is an error too.
bool ReadHosts(const std::string& file, std::vector<HostSpec>* hosts, std::string* err);

// One host in the file's own grammar with every field spelled out
// (--dump-hosts): "user@name:port slots=N cmd=PATH", the unset ones left out.
std::string FormatHost(const HostSpec& h);

#endif
