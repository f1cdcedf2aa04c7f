#pragma once
/*!
  \file bag.h
  \brief Robot recordings as bags, read without a ROS installation at run time: ROS 1 `.bag`
  (through Debian's rosbag_storage, when this build found it), ROS 2 `.mcap` and `.db3` (read from
  their published specifications: MCAP records and chunks, zstd or lz4; rosbag2's SQLite schema),
  or a ROS 2 bag folder with its `metadata.yaml`. Messages come out raw (their serialized bytes)
  and are decoded by the functions of messages.h, for exactly the message types `import-bag` reads.

  Times: `std::int64_t` nanoseconds since 1970 (ROS time), the recorder's clock (log time) for a
  message, the sender's clock for a header stamp.

  Every failure throws yawdepth::Error with a one-line message that starts with the bag's path: an
  unknown container, a truncated or corrupt bag ("... truncated: read 1234567 of 2000000 bytes,
  last good message at t = ..."), an unknown compression, a format this build cannot read.
*/
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace yawdepth {

/*! \brief A bag's container. */
enum class BagFormat {
  Ros1,   //!< ROS 1 `.bag` (format 2.0), through rosbag_storage
  Mcap,   //!< MCAP (ROS 2's default since Iron), messages in CDR (`ros2msg` schemas)
  Sqlite3 //!< rosbag2's `.db3` (SQLite), messages in CDR
};

/*! \brief "ros1", "mcap", "db3". */
const char *toString(BagFormat f);

/*! \brief The formats this build reads (those whose libraries were found when it was built). */
std::vector<BagFormat> readableBagFormats();

/*! \brief How a topic's messages are serialized. */
enum class BagEncoding {
  Ros1, //!< ROS 1 serialization (little-endian, no alignment)
  Cdr   //!< ROS 2's CDR (XCDR1, the 4-byte encapsulation header says the byte order)
};

/*! \brief One topic of a bag. */
struct BagTopic {
  std::string name;           //!< "/camera/image_raw"
  /*! The message type, ROS 1 spelling ("sensor_msgs/Image"): a ROS 2 "sensor_msgs/msg/Image" is
      given without its "/msg". */
  std::string type;
  BagEncoding encoding = BagEncoding::Ros1; //!< how its messages are serialized
  std::uint64_t messages = 0; //!< count (from the bag's index or summary; 0 when it has none)
};

/*! \brief One message, valid only during the visit that receives it. */
struct BagMessage {
  const BagTopic *topic = nullptr; //!< its topic (one of BagReader::topics())
  std::int64_t log_time = 0;       //!< when the recorder received it (ns)
  const std::uint8_t *data = nullptr; //!< the serialized message
  std::size_t size = 0;               //!< its length (bytes)
};

/*! \brief Which messages to read. */
struct BagReadOptions {
  std::vector<std::string> topics; //!< topic names; empty: every topic
  std::int64_t start = INT64_MIN;  //!< first log time read (ns), inclusive
  std::int64_t end = INT64_MAX;    //!< last log time read (ns), inclusive
};

/*!
  \brief An open bag. read() streams the messages in bounded memory (a chunk at a time: a 10 GB
  bag is never held whole), in log-time order for ROS 1 and `.db3`, in file order for MCAP (which
  is log-time order for every recorder we know; callers that need order sort what they keep).
*/
class BagReader {
public:
  virtual ~BagReader() = default;
  /*! \brief The container. */
  virtual BagFormat format() const = 0;
  /*! \brief The bag's path as given (folders: the folder). */
  virtual const std::string &path() const = 0;
  /*! \brief Every topic, by name. */
  virtual const std::vector<BagTopic> &topics() const = 0;
  /*!
    \brief Calls `visit` for each message of the selected topics and times; `visit` returns false
    to stop early. Throws yawdepth::Error on a corrupt or truncated bag, after the messages read
    before the damage were visited (the message says how far it got).
  */
  virtual void read(const BagReadOptions &options, const std::function<bool(const BagMessage &)> &visit) = 0;
  /*! \brief The topic named so, or nullptr. */
  const BagTopic *topic(const std::string &name) const;
  /*! \brief "name (type, N messages)" for every topic, comma-separated: for the messages that name a missing topic. */
  std::string topicList() const;
};

/*!
  \brief Open a bag by its content (not its name): `#ROSBAG V2.0` is ROS 1, the MCAP magic is
  MCAP, an SQLite file is `.db3`; a folder is a ROS 2 bag folder (its `metadata.yaml` names the
  storage files; several `.db3` or `.mcap` files are read in order).
  \throws yawdepth::Error for an unreadable or unknown file, or a format this build does not read
  ("... is a ROS 1 bag, and this build was made without rosbag_storage").
*/
std::unique_ptr<BagReader> openBag(const std::string &path);

} // namespace yawdepth
