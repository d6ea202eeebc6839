#include "core/sim/world.h"

namespace lanemap::sim {

LabelClass labelFor(const World& world, const GroundSample& g, int64_t ego_lanelet) {
  switch (g.surface) {
    case Surface::kDashedPaint: return LabelClass::kDashedLine;
    case Surface::kSolidPaint: return LabelClass::kSolidLine;
    case Surface::kCrosswalkPaint: return LabelClass::kCrosswalk;
    case Surface::kStopLinePaint: return LabelClass::kStopLine;
    case Surface::kCurb: return LabelClass::kCurb;
    case Surface::kAsphalt: {
      if (ego_lanelet < 0 || g.lanelet < 0) return LabelClass::kBackground;
      const auto off = world.laneOffset(ego_lanelet, g.lanelet);
      if (!off) return LabelClass::kBackground;
      switch (*off) {
        case 0: return LabelClass::kLaneEgo;
        case -1: return LabelClass::kLaneLeft;
        case 1: return LabelClass::kLaneRight;
        case -2: return LabelClass::kLaneLeftLeft;
        case 2: return LabelClass::kLaneRightRight;
        default: return LabelClass::kBackground;
      }
    }
    default: return LabelClass::kBackground;
  }
}

}  // namespace lanemap::sim
