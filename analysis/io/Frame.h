#pragma once
/// \file Frame.h
/// The analysis works on common::TrajectoryFrame, the frame every trajectory reader returns
/// (common/TrajectoryFrame.h); these names keep the analysis code short.
#include "common/TrajectoryFrame.h"

namespace granagg::analysis {

using Frame = common::TrajectoryFrame;
using common::TrajectoryError;

}  // namespace granagg::analysis
