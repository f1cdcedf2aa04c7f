// openBag(): a bag told by its content, a ROS 2 bag folder by its metadata.yaml.
#include "readers.h"

#include <algorithm>
#include <cctype>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <yaml-cpp/yaml.h>
#include <yawdepth/core/files.h>
#include <yawdepth/error.h>

namespace yawdepth {

const char *toString(BagFormat f)
{
  switch (f) {
  case BagFormat::Ros1:
    return "ros1";
  case BagFormat::Mcap:
    return "mcap";
  case BagFormat::Sqlite3:
    return "db3";
  }
  return "?";
}

std::vector<BagFormat> readableBagFormats()
{
  std::vector<BagFormat> f;
#ifdef YAWDEPTH_BAG_ROS1
  f.push_back(BagFormat::Ros1);
#endif
#ifdef YAWDEPTH_BAG_MCAP
  f.push_back(BagFormat::Mcap);
#endif
#ifdef YAWDEPTH_BAG_DB3
  f.push_back(BagFormat::Sqlite3);
#endif
  return f;
}

const BagTopic *BagReader::topic(const std::string &name) const
{
  for (const BagTopic &t : topics())
    if (t.name == name)
      return &t;
  return nullptr;
}

std::string BagReader::topicList() const
{
  std::string s;
  for (const BagTopic &t : topics())
    s += (s.empty() ? "" : ", ") + t.name + " (" + t.type + ", " + std::to_string(t.messages) + " messages)";
  return s.empty() ? std::string("no topics") : s;
}

namespace {

namespace fs = std::filesystem;

const char kRos1Magic[] = "#ROSBAG V2.0\n";
const unsigned char kMcapMagic[] = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};
const char kSqliteMagic[] = "SQLite format 3"; // followed by a NUL

std::string head(const std::string &path, std::size_t n)
{
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw Error(path + ": cannot open the bag");
  std::string s(n, '\0');
  in.read(&s[0], std::streamsize(n));
  s.resize(std::size_t(in.gcount()));
  return s;
}

[[noreturn]] [[maybe_unused]] void notBuilt(const std::string &path, const char *what, const char *library)
{
  throw Error(path + ": is " + what + ", and this build was made without " + library +
              " (yawdepth --version lists the bag formats it reads)");
}

std::unique_ptr<BagReader> openFile(const std::string &path, const std::string &name,
                                    const std::vector<std::string> &files)
{
  const std::string h = head(files.front(), 16);
  if (h.compare(0, std::strlen(kRos1Magic), kRos1Magic) == 0) {
#ifdef YAWDEPTH_BAG_ROS1
    if (files.size() > 1)
      throw Error(name + ": several ROS 1 bags in one folder: give one bag file");
    return bag_detail::openRos1(path);
#else
    notBuilt(path, "a ROS 1 bag", "rosbag_storage (Debian: librosbag-storage-dev)");
#endif
  }
  if (h.size() >= sizeof kMcapMagic && std::memcmp(h.data(), kMcapMagic, sizeof kMcapMagic) == 0) {
#ifdef YAWDEPTH_BAG_MCAP
    return bag_detail::openMcap(name, files);
#else
    notBuilt(path, "an MCAP file", "zstd, lz4 and zlib (Debian: libzstd-dev, liblz4-dev, zlib1g-dev)");
#endif
  }
  if (h.size() == 16 && h.compare(0, 15, kSqliteMagic) == 0 && h[15] == '\0') {
#ifdef YAWDEPTH_BAG_DB3
    return bag_detail::openDb3(name, files);
#else
    notBuilt(path, "an SQLite (.db3) bag", "SQLite (Debian: libsqlite3-dev)");
#endif
  }
  if (h.rfind("#ROSBAG", 0) == 0)
    throw Error(files.front() + ": a ROS bag of another version than 2.0 ('" + h.substr(0, h.find('\n')) + "')");
  throw Error(files.front() + ": not a bag (neither ROS 1 '#ROSBAG V2.0', MCAP nor SQLite by its first bytes)");
}

/*! The storage files a ROS 2 bag folder's metadata.yaml names, in order. */
std::vector<std::string> folderFiles(const std::string &dir)
{
  const fs::path meta = fs::path(dir) / "metadata.yaml";
  if (!fs::exists(meta)) {
    // No metadata: the folder's one .mcap or .db3 file(s), in name order.
    std::vector<std::string> files;
    std::error_code ec;
    for (const auto &e : fs::directory_iterator(dir, ec)) {
      std::string ext = e.path().extension().string();
      if (ext == ".zstd") // rosbag2's FILE compression: bag_0.db3.zstd
        ext = e.path().stem().extension().string();
      if (e.is_regular_file() && (ext == ".mcap" || ext == ".db3" || ext == ".bag"))
        files.push_back(e.path().string());
    }
    if (ec)
      throw Error(dir + ": cannot read the folder: " + ec.message());
    if (files.empty())
      throw Error(dir + ": a folder without metadata.yaml and without .mcap, .db3 or .bag files");
    std::sort(files.begin(), files.end());
    return files;
  }
  YAML::Node root;
  try {
    root = YAML::LoadFile(meta.string());
  } catch (const YAML::Exception &e) {
    throw Error(meta.string() + ":" + std::to_string(e.mark.line + 1) + ": not YAML: " + e.msg);
  }
  const YAML::Node info = root["rosbag2_bagfile_information"];
  if (!info || !info.IsMap())
    throw Error(meta.string() + ": no rosbag2_bagfile_information (not a rosbag2 metadata file)");
  // rosbag2_compression: zstd is its one compressor; the modes are undone by the bytes (openRosbag2).
  const auto scalar = [&](const char *key) {
    const YAML::Node n = info[key];
    return n && n.IsScalar() ? n.Scalar() : std::string();
  };
  const std::string compression = scalar("compression_format");
  std::string mode = scalar("compression_mode");
  std::transform(mode.begin(), mode.end(), mode.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  if (!compression.empty() && compression != "zstd")
    throw Error(meta.string() + ": compression_format '" + compression + "' (rosbag2 compresses with zstd, which yawdepth reads)");
  if (!mode.empty() && mode != "none" && mode != "file" && mode != "message")
    throw Error(meta.string() + ": compression_mode '" + scalar("compression_mode") + "' (rosbag2 writes FILE, MESSAGE or NONE)");
  const YAML::Node paths = info["relative_file_paths"];
  if (!paths || !paths.IsSequence() || paths.size() == 0)
    throw Error(meta.string() + ": rosbag2_bagfile_information.relative_file_paths is missing or empty");
  std::vector<std::string> files;
  for (const YAML::Node &p : paths) {
    if (!p.IsScalar())
      throw Error(meta.string() + ":" + std::to_string(p.Mark().line + 1) + ": a relative_file_paths entry is not a name");
    fs::path f = fs::path(dir) / p.Scalar();
    if (!fs::exists(f) && fs::exists(fs::path(dir) / f.filename()))
      f = fs::path(dir) / f.filename(); // rosbag2 once wrote the folder into the relative path
    if (!fs::is_regular_file(f))
      throw Error(meta.string() + ": names " + p.Scalar() + ", which is not in " + dir);
    files.push_back(f.string());
  }
  return files;
}

} // namespace

std::unique_ptr<BagReader> openBag(const std::string &path)
{
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (ec || !fs::exists(st))
    throw Error(path + ": no such bag");
  std::vector<std::string> files;
  if (fs::is_directory(st)) {
    files = folderFiles(path);
  } else {
    checkInputFile(path);
    files = {path};
  }
#ifdef YAWDEPTH_BAG_ZSTD
  return bag_detail::openRosbag2(path, files, openFile);
#else
  for (const std::string &f : files)
    if (fs::is_regular_file(f) && head(f, 4) == std::string("\x28\xb5\x2f\xfd", 4))
      notBuilt(f, "a zstd-compressed bag (rosbag2's FILE compression)", "zstd (Debian: libzstd-dev)");
  return openFile(files.front(), path, files);
#endif
}

} // namespace yawdepth
