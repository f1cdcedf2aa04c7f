// TEMPORARY (branch bag-ros1): stand-ins for the ROS 2 side (mcap_reader.cpp, db3_reader.cpp,
// messages_cdr.cpp), so that the module links before that side is merged. Drop this file and its
// line in CMakeLists.txt at the merge.
#include "readers.h"

#include <yawdepth/error.h>

namespace yawdepth {
namespace bag_detail {

std::unique_ptr<BagReader> openMcap(const std::string &path, const std::vector<std::string> &)
{
  throw Error(path + ": the MCAP reader is not built yet");
}
std::unique_ptr<BagReader> openDb3(const std::string &path, const std::vector<std::string> &)
{
  throw Error(path + ": the .db3 reader is not built yet");
}

namespace cdr {
#define YAWDEPTH_CDR_PLACEHOLDER(T, fn)                                                                                \
  T fn(const BagMessage &m) { throw Error(messageWhere(m) + "the CDR decoder is not built yet"); }
YAWDEPTH_CDR_PLACEHOLDER(ImageMessage, decodeImage)
YAWDEPTH_CDR_PLACEHOLDER(CompressedImageMessage, decodeCompressedImage)
YAWDEPTH_CDR_PLACEHOLDER(CameraInfoMessage, decodeCameraInfo)
YAWDEPTH_CDR_PLACEHOLDER(PoseMessage, decodePose)
YAWDEPTH_CDR_PLACEHOLDER(OdometryMessage, decodeOdometry)
YAWDEPTH_CDR_PLACEHOLDER(TfMessage, decodeTf)
YAWDEPTH_CDR_PLACEHOLDER(JointStateMessage, decodeJointState)
#undef YAWDEPTH_CDR_PLACEHOLDER
} // namespace cdr

} // namespace bag_detail
} // namespace yawdepth
