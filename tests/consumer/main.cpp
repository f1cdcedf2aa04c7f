// Consumer of the installed package: side view, 20 mm forward, a point 1 m away.
#include <cmath>
#include <iostream>
#include <yawdepth/estimation/two_view.h>
#include <yawdepth/io/files.h>
#include <yawdepth/pipeline/pipeline.h>

int main()
{
  const yawdepth::CameraModel camera = yawdepth::CameraModel::brown(1700, 1700, 320, 240, {});
  const yawdepth::YawRig rig(Eigen::Vector3d(-0.15, 0, 0));
  yawdepth::MotionSample prev, cur;
  cur.frame = 1;
  cur.z = 0.02;
  prev.yaw = cur.yaw = M_PI / 2;
  // At side view the camera moves 20 mm toward its -X: a point at depth 1 m shifts by +34 px.
  const yawdepth::PointEstimate e =
      yawdepth::estimateExact(camera, rig, prev, cur, Eigen::Vector2d(320, 240), Eigen::Vector2d(354, 240));
  std::cout << yawdepth::toString(e.status) << " zc=" << e.c_P.z() << "\n";
  // The same point as a track, through the one entry point (every method by name).
  yawdepth::Track track;
  track.observations = {{0, 320, 240}, {1, 354, 240}};
  yawdepth::PipelineOptions options;
  options.method = yawdepth::methodFromString("exact");
  const yawdepth::PipelineResult r = yawdepth::estimatePoints(camera, rig, {prev, cur}, {track}, options);
  std::cout << "estimatePoints: " << yawdepth::toString(r.points[0].status) << " zc=" << r.points[0].c_P.z() << "\n";
  return e.ok() && std::abs(e.c_P.z() - 1.0) < 1e-9 && r.points[0].ok() && std::abs(r.points[0].c_P.z() - 1.0) < 1e-9
             ? 0
             : 1;
}
