// The files the program reads and writes, and the rules for both (man
// page FILES, SECURITY, LIMITS). An input is opened without blocking (a
// FIFO with no writer, a terminal, a device) and must be a regular file no
// larger than its bound, checked before a byte is read. An output is
// written into a new file made in its directory (mkstemp: O_EXCL, never
// through a link planted there) and renamed onto its name, which must be
// new or a regular file and none of the run's inputs. The outputs of one
// run are written into a private directory inside the output directory and
// moved out together at the end, so that a directory never holds the
// results of two runs.
#ifndef RADIOSITY_FILES_H
#define RADIOSITY_FILES_H

#include <sys/types.h>

#include <cstdint>
#include <cstdio>
#include <functional>
#include <string>
#include <vector>

// Size bounds of the files read (LIMITS in the man page).
constexpr uint64_t kMaxSceneBytes = 4ull << 30;       // an OBJ: some 40 million faces
constexpr uint64_t kMaxMtlBytes = 64ull << 20;        // an MTL
constexpr uint64_t kMaxReferenceBytes = 4ull << 30;   // --reference CSV
constexpr uint64_t kMaxCheckpointBytes = 4ull << 30;  // --resume: 8 M elements fit
constexpr uint64_t kMaxHostsBytes = 1ull << 20;       // -H FILE
constexpr uint64_t kMaxSecretBytes = 64ull << 10;     // --secret FILE

// The same file under any of its names (hard links, symbolic links).
struct FileId {
  dev_t dev = 0;
  ino_t ino = 0;
  bool operator==(const FileId& o) const { return dev == o.dev && ino == o.ino; }
};

// Opens PATH to read: refused unless it is a regular file of at most
// max_bytes. -1 with *err = what is wrong, without the name ("not a
// regular file"). *id: its identity.
int OpenInput(const std::string& path, uint64_t max_bytes, std::string* err,
              FileId* id = nullptr);
// The same as a stdio stream.
std::FILE* OpenInputFile(const std::string& path, uint64_t max_bytes, std::string* err,
                         FileId* id = nullptr);
// The whole of such a file (one that grows past max_bytes while read is
// refused too); *err = "PATH: what".
bool ReadInput(const std::string& path, uint64_t max_bytes, std::string* bytes, std::string* err,
               FileId* id = nullptr);

// A file the run reads, by what it is to the user ("the scene").
struct Input {
  std::string what, path;
  FileId id;
};
// The input PATH, for the checks below; false with *err when it cannot be
// looked at.
bool AddInput(const std::string& what, const std::string& path, std::vector<Input>* inputs,
              std::string* err);

// "" when PATH may be written (a new name, or a regular file that is none
// of `inputs`), else why not ("is the scene", "is not a regular file").
std::string Unwritable(const std::string& path, const std::vector<Input>& inputs);

// Writes `data` to PATH (the rules above; `sync`: on disk before the
// rename, so that after a crash PATH holds the old file or the whole new
// one). *err = "PATH: what".
bool WriteFileAtomic(const std::string& path, const std::string& data, std::string* err,
                     bool sync = false);
// The same for a file written piece by piece: `body` hands its bytes to
// the sink (false: a write failed, errno says why) and returns whether all
// went, so that a large output (the PLY, glTF buffer of 10^6 elements:
// hundreds of MB) is never held whole in memory.
using FileSink = std::function<bool(const char* data, size_t size)>;
bool WriteFileAtomic(const std::string& path, const std::function<bool(const FileSink&)>& body,
                     std::string* err, bool sync = false);

// The directory of PATH: "." for a bare name.
std::string DirName(const std::string& path);

// The outputs of one run: written into DIR/.radiosity-XXXXXX, moved onto
// DIR/NAME together by Commit().
class Staging {
 public:
  Staging() = default;
  Staging(const Staging&) = delete;
  Staging& operator=(const Staging&) = delete;
  ~Staging();  // removes what was not committed
  bool Open(const std::string& dir, std::string* err);
  // Where NAME is written during the run.
  std::string Path(const std::string& name) const { return stage_ + "/" + name; }
  // Checks every file written against the rules and `inputs`, then, with
  // SIGINT, SIGTERM and SIGHUP held, renames each onto DIR/NAME and
  // removes what `ours` says an earlier run left in DIR that this one did
  // not write. False with *err (and nothing moved) when a name may not be
  // written.
  bool Commit(const std::vector<Input>& inputs, const std::function<bool(const std::string&)>& ours,
              std::string* err);
  // Removes the private directory and what is in it.
  void Discard();

 private:
  std::string dir_, stage_;
};

#endif
