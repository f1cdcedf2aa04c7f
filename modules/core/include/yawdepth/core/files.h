#pragma once
/*
  core/files.h, for the build tree only (not installed: the modules' and the command line's own
  file safety; CMakeLists.txt of yawdepth::core).

  Files in and out, the careful way: inputs read as streams with a bound on their size, outputs
  written atomically without ever replacing an input, a device or a read-only file.

  Inputs. Only a regular file or a pipe (FIFO, process substitution, standard input as
  `/dev/stdin`) is read; a folder, a character or block device (`/dev/zero`, a terminal) or a socket
  is refused with a reason before it is opened. Opening a FIFO that no program writes to waits for
  a writer, as `cat` does. Text inputs are read a line at a time, with a limit on the length of a
  line and on the size of the whole file (InputLimits), so that an endless input ends in a one-line
  error instead of eating the machine's memory.

  Outputs. A regular file is written to a temporary file in the same folder, then renamed over
  the target once complete: a failed or interrupted run never leaves a partial file that looks
  complete (with removeTemporaryFilesOnSignals(), not even after SIGINT, SIGTERM or SIGHUP). A
  symbolic link is followed: the file it points to is replaced and the link stays. A character
  device or a pipe (`/dev/null`, `/dev/stdout`, a FIFO) is written through, and stays what it is.
  An existing file without write permission is refused (even for root), as is a folder. Several
  files that belong together (a camera file in two formats) are committed together by AtomicFiles.

  Every failure throws yawdepth::Error with a one-line message that starts with the path.
*/
#include <cstddef>
#include <string>
#include <vector>
#include <yawdepth/core/input_limits.h>

namespace yawdepth {

/*
  Throws yawdepth::Error unless `path` names a regular file or a pipe (symbolic links
  followed): "<path>: cannot read: is a folder", "... is a character device, not a regular file or a
  pipe", "... no such file", ...
*/
void checkInputFile(const std::string &path);

/*
  A text input read as a stream, line by line, within InputLimits.

  LF or CRLF line ends (the CR is kept: callers strip it). A line longer than max_line_bytes or a
  file larger than max_bytes throws "<path>:<line>: line longer than N bytes" or "<path>: larger
  than N bytes (...)".
*/
class TextInput {
public:
  /* Open `path` (checkInputFile() first). path: The file. limits: Its bounds. */
  explicit TextInput(const std::string &path, const InputLimits &limits = InputLimits());
  ~TextInput();
  TextInput(const TextInput &) = delete;
  TextInput &operator=(const TextInput &) = delete;

  /* The next line, without its '\n'; false at the end of the file. line: Receives it. */
  bool getline(std::string &line);
  /* The rest of the file, whole (within max_bytes; the line limit does not apply). */
  std::string readAll();
  /* Number of the line last returned by getline() (1-based). */
  std::size_t lineNumber() const { return line_number_; }
  /* The path, as given. */
  const std::string &path() const { return path_; }

private:
  bool fill();

  std::string path_;
  InputLimits limits_;
  int fd_ = -1;
  std::vector<char> buffer_;
  std::size_t begin_ = 0;
  std::size_t end_ = 0;
  std::size_t total_ = 0;
  std::size_t line_number_ = 0;
  bool eof_ = false;
};

/* The whole of a text file, at most `max_bytes` (TextInput::readAll()). */
std::string readTextFile(const std::string &path, std::size_t max_bytes);

/*
  The whole of a binary file (an image), at most `max_bytes`; the same checks as
  checkInputFile(), and an empty file is an error.
*/
std::vector<unsigned char> readBinaryFile(const std::string &path, std::size_t max_bytes);

/*
  True when both paths exist and are the same file (device and inode, after symbolic
  links: hard links, `./a` and `a` count as the same).
*/
bool sameFile(const std::string &a, const std::string &b);

/* A path named by a command-line option, for messages ("--out t.csv"). */
struct NamedPath {
  std::string option; // The option, e.g. "--out".
  std::string path;   // Its value.
};

/*
  Before anything is written: throws yawdepth::Error when an output would replace an input
  (same file, see sameFile()), when two outputs are the same file, or when an output's name is
  empty or a folder. Outputs that are character devices (`/dev/null`) may repeat. "-" is refused
  (writers would make a file named "-"): a program that sends an output to standard output for
  "-" leaves that output out of `outputs`.
  inputs: The files the command reads.
  outputs: The files it will write.
*/
void checkOutputs(const std::vector<NamedPath> &inputs, const std::vector<NamedPath> &outputs);

/*
  Files committed together: each add() checks its target and writes a temporary file
  beside it; commit() renames them all over their targets (or writes through to devices and
  pipes). Until commit(), nothing at any target has changed; the destructor removes what was not
  committed.
*/
class AtomicFiles {
public:
  AtomicFiles() = default;
  ~AtomicFiles();
  AtomicFiles(const AtomicFiles &) = delete;
  AtomicFiles &operator=(const AtomicFiles &) = delete;

  /* Stage `contents` for `path`. path: The target. contents: Its bytes. */
  void add(const std::string &path, const std::string &contents);
  /* Rename (or write through) every staged file. */
  void commit();

private:
  struct Entry {
    std::string target;   // the file replaced (symbolic links resolved)
    std::string temp;     // temporary file beside it; empty when written through
    std::string contents; // kept only for write-through targets
    std::string shown;    // the path as given, for messages
    int slot = -1;        // its registration for removeTemporaryFilesOnSignals()
  };
  std::vector<Entry> entries_;
};

/*
  Write `contents` to `path` atomically (AtomicFiles with one file).
  path: The target. contents: Its bytes.
*/
void writeFileAtomically(const std::string &path, const std::string &contents);

/*
  A scratch file in the system's temporary folder (`$TMPDIR`, else `/tmp`), for a library that
  must hand a file to another one (an SQLite bag decompressed for SQLite, say): created empty and
  unique (mkstemps), removed by the destructor, and by the handlers of
  removeTemporaryFilesOnSignals() when the program is interrupted.
*/
class ScratchFile {
public:
  /*
    suffix: The end of its name (e.g. ".db3").
    Throws yawdepth::Error when it cannot be created.
  */
  explicit ScratchFile(const std::string &suffix);
  ~ScratchFile();
  ScratchFile(const ScratchFile &) = delete;
  ScratchFile &operator=(const ScratchFile &) = delete;
  /* Its path. */
  const std::string &path() const { return path_; }

private:
  std::string path_;
  int slot_ = -1;
};

/*
  Install handlers for SIGINT, SIGTERM and SIGHUP (where the program has none) that remove
  the temporary files of writes in progress, then end the program by the same signal. For
  programs, such as the `yawdepth` command line; a library never calls it.
*/
void removeTemporaryFilesOnSignals();

} // namespace yawdepth
