#pragma once
/*!
  \file refine/window_estimator.h
  \brief Compatibility header: the window estimator lives in yawdepth::window
  (yawdepth/window/window_estimator.h), a module without Ceres.
*/
#include <yawdepth/window/window_estimator.h>
