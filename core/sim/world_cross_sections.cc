// The world's roads: cross-sections (the two directions of a way between two intersections),
// their layout (lanes, pockets, bays, parking, bike lanes, curbs, sidewalks), their sections and the
// lanelets and line strings of the truth. Part of buildWorld (core/sim/world_build.h).
#include "core/sim/world_build.h"

namespace lanemap::sim::world_build {

void Builder::groupCrossSections() {
  std::set<int64_t> done;
  for (const auto& r : sk_.roads()) {
    if (done.count(r.id)) continue;
    const skeleton::AtomicRoad* rev = r.reverse_id >= 0 ? sk_.road(r.reverse_id) : nullptr;
    CrossSection xs;
    xs.key = static_cast<int64_t>(xss_.size());
    if (rev && !r.along_way && rev->along_way) {
      xs.ref = rev;
      xs.rev = &r;
    } else {
      xs.ref = &r;
      xs.rev = rev;
    }
    done.insert(r.id);
    if (rev) done.insert(rev->id);
    xs.two_way = xs.rev != nullptr;
    const auto hw = xs.ref->tags.find("highway");
    xs.highway = hw == xs.ref->tags.end() ? std::string("road") : hw->second;
    layoutCrossSection(xs);
    xs_of_road_[xs.ref->id] = xs.key;
    if (xs.rev) xs_of_road_[xs.rev->id] = xs.key;
    xss_.push_back(std::move(xs));
  }
}

void Builder::layoutCrossSection(CrossSection& xs) {
  const osm::Tags& tags = xs.ref->tags;
  auto r = rngFor(o_.seed, xs.ref->id, 2);
  LaneCounts counts = laneCountsFor(tags, !xs.two_way);
  // A one-way road against its way (oneway=-1): its lanes are "forward" of its reference road.
  const std::string cls = baseClass(xs.highway);
  // Lane widths: width / lanes when tagged, else the class default with a per-lane variation.
  const int total = counts.forward + counts.backward;
  double tagged = -1.0;
  if (auto it = tags.find("width"); it != tags.end()) {
    char* end = nullptr;
    const double w = std::strtod(it->second.c_str(), &end);
    if (end != it->second.c_str() && w > 0.0) tagged = w / total;
  }
  const double base = o_.default_lane_width_m > 0 ? o_.default_lane_width_m : defaultLaneWidth(xs.highway);
  auto laneWidth = [&]() {
    const double w = tagged > 0 ? tagged : base + uni(r, -o_.lane_width_jitter_m, o_.lane_width_jitter_m);
    return std::clamp(w, o_.lane_width_min_m, o_.lane_width_max_m);
  };
  const std::string tl_key_f = xs.two_way ? "turn:lanes:forward" : "turn:lanes";
  const auto tl_f = tags.count(tl_key_f) ? osm::splitTurnLanes(tags.at(tl_key_f)) : std::vector<std::string>();
  const auto tl_b = tags.count("turn:lanes:backward") ? osm::splitTurnLanes(tags.at("turn:lanes:backward")) : std::vector<std::string>();
  for (int k = 0; k < 2; ++k) {
    Side& sd = xs.side[k];
    sd.sigma = k == 0 ? -1 : +1;
    const int n = k == 0 ? counts.forward : counts.backward;
    const skeleton::AtomicRoad* road = k == 0 ? xs.ref : xs.rev;
    if (n > 0 && road) {
      sd.dir = k == 0 ? +1 : -1;
      sd.road_id = road->id;
      sd.from_node = road->from;
      sd.to_node = road->to;
      for (int i = 0; i < n; ++i) sd.lane_w.push_back(laneWidth());
      // turn:lanes lists lanes left to right in the driving direction; inner = left in RHT.
      const auto& tl = k == 0 ? tl_f : tl_b;
      sd.turn.assign(n, "");
      if (static_cast<int>(tl.size()) == n) {
        for (int i = 0; i < n; ++i) sd.turn[i] = tl[o_.right_hand_traffic ? i : n - 1 - i];
      }
    }
    // Curb-side strip.
    if (isMinorStreet(cls) && chance(r, o_.p_parking_lane)) {
      sd.edge = Edge::kParking;
      sd.edge_w = uni(r, 2.2, 2.5);
    } else if (isMajor(cls) && chance(r, o_.p_bike_lane)) {
      sd.edge = Edge::kBike;
      sd.edge_w = uni(r, 1.5, 1.8);
    }
    const double p_sw = cls == "service" ? o_.p_sidewalk / 3.0 : (cls == "motorway" || cls == "trunk" ? 0.0 : o_.p_sidewalk);
    if (chance(r, p_sw)) sd.sidewalk_w = uni(r, 1.5, 3.0);
  }
  xs.anchor = xs.two_way ? 0.0 : xs.side[0].lanesWidth() / 2.0;
}

void Builder::computeNodeInfo() {
  for (const auto& in : sk_.intersections()) {
    std::set<int64_t> xset;
    for (int64_t r : in.incoming) xset.insert(xs_of_road_.at(r));
    for (int64_t r : in.outgoing) xset.insert(xs_of_road_.at(r));
    degree_[in.id] = static_cast<int>(xset.size());
    double rmax = 0.0;
    for (int64_t x : xset) rmax = std::max(rmax, xss_[x].halfWidth());
    min_trim_[in.id] = in.dead_end ? 0.0 : rmax + 1.0;
  }
}

int Builder::degree(int64_t node) const {
  auto it = degree_.find(node);
  return it == degree_.end() ? 0 : it->second;
}

std::vector<double> Builder::columnValues(const CrossSection& xs, const Section& sec, double s) const {
  std::vector<double> vals(sec.cols.size());
  // Columns are stored left -> right; compute side offsets first, then map.
  std::vector<double> side_vals[2];
  for (int k = 0; k < 2; ++k) {
    const Side& sd = xs.side[k];
    double pos = xs.anchor;
    auto push = [&](double w) {
      pos += sd.sigma * w;
      side_vals[k].push_back(pos);
    };
    if (sec.pocket_in[k]) push(sd.pocketWidth(s));
    for (double w : sd.lane_w) push(w);
    if (sd.edge != Edge::kNone) push(sd.edge_w);
    else if (sec.bay_in[k]) push(sd.bayWidth(s));
    if (sd.sidewalk_w > 0) push(sd.sidewalk_w);
  }
  // Left -> right: backward side outer -> inner, anchor, forward side inner -> outer.
  size_t i = 0;
  for (auto it = side_vals[1].rbegin(); it != side_vals[1].rend(); ++it) vals[i++] = *it;
  vals[i++] = xs.anchor;
  for (double v : side_vals[0]) vals[i++] = v;
  return vals;
}

std::vector<Column> Builder::columnTemplate(const CrossSection& xs, const Section& sec) const {
  std::vector<Column> side_cols[2];
  for (int k = 0; k < 2; ++k) {
    const Side& sd = xs.side[k];
    if (sec.pocket_in[k]) side_cols[k].push_back({k, ColKind::kPocketDiv, -1});
    for (int i = 0; i < static_cast<int>(sd.lane_w.size()); ++i) side_cols[k].push_back({k, ColKind::kLaneOuter, i});
    if (sd.edge != Edge::kNone || sec.bay_in[k]) side_cols[k].push_back({k, ColKind::kEdgeOuter, -1});
    if (sd.sidewalk_w > 0) side_cols[k].push_back({k, ColKind::kSidewalkOuter, -1});
  }
  std::vector<Column> cols(side_cols[1].rbegin(), side_cols[1].rend());
  cols.push_back({-1, ColKind::kAnchor, -1});
  cols.insert(cols.end(), side_cols[0].begin(), side_cols[0].end());
  return cols;
}

LineType Builder::lineTypeOf(const CrossSection& xs, const Section& sec, const Column& c) const {
  switch (c.kind) {
    case ColKind::kAnchor:
      if (xs.two_way) {
        const std::string cls = baseClass(xs.highway);
        return isMajor(cls) || cls == "motorway" ? LineType::kSolidSolid : LineType::kSolid;
      }
      return xs.side[1].edge != Edge::kNone ? LineType::kSolid : LineType::kCurb;
    case ColKind::kPocketDiv: return LineType::kDashed;
    case ColKind::kLaneOuter: {
      const Side& sd = xs.side[c.side];
      if (c.lane + 1 < static_cast<int>(sd.lane_w.size())) return LineType::kDashed;
      return sd.edge != Edge::kNone || sec.bay_in[c.side] ? LineType::kSolid : LineType::kCurb;
    }
    case ColKind::kEdgeOuter: return LineType::kCurb;
    case ColKind::kSidewalkOuter: return LineType::kVirtual;  // not a LineString
  }
  return LineType::kVirtual;
}

void Builder::chooseTrim(CrossSection& xs) {
  const double L = xs.line.length();
  const double raw = std::max(xs.ref->length, 1e-6);
  double sb = xs.ref->s_begin, se = xs.ref->s_end;
  if (xs.rev) {
    sb = std::max(sb, xs.rev->length - xs.rev->s_end);
    se = std::min(se, xs.rev->length - xs.rev->s_begin);
  }
  sb *= L / raw;
  se *= L / raw;
  sb = std::max(sb, min_trim_[xs.ref->from]);
  se = std::min(se, L - min_trim_[xs.ref->to]);
  constexpr double kMin = 4.0;
  if (se - sb < kMin) {
    const double mid = std::clamp((sb + se) / 2.0, 0.0, L);
    sb = std::max(0.0, mid - kMin / 2);
    se = std::min(L, sb + kMin);
    sb = std::max(0.0, se - kMin);
  }
  xs.sb = sb;
  xs.se = std::max(se, sb + 0.05);
}

void Builder::choosePocketsAndBays(CrossSection& xs) {
  auto r = rngFor(o_.seed, xs.ref->id, 3);
  const std::string cls = baseClass(xs.highway);
  const bool pocket_class = cls != "motorway" && cls != "trunk" && cls != "service";
  for (int k = 0; k < 2; ++k) {
    Side& sd = xs.side[k];
    if (sd.dir == 0 || !pocket_class) continue;
    if (degree(sd.to_node) < 3 || !chance(r, o_.p_turn_pocket)) continue;
    const double len = uni(r, 30.0, 50.0);
    const double start = k == 0 ? xs.se - len : xs.sb + len;
    const double room = k == 0 ? start - xs.sb : xs.se - start;
    if (room < 20.0) continue;
    sd.pocket = true;
    sd.pocket_start = start;
    sd.pocket_taper = std::min(15.0, len / 2.0);
    sd.pocket_w = std::clamp(sd.lane_w.front() + uni(r, -0.1, 0.1), o_.lane_width_min_m, o_.lane_width_max_m);
  }
  if (xs.side[0].pocket && xs.side[1].pocket && xs.side[1].pocket_start > xs.side[0].pocket_start - 10.0) {
    xs.side[1].pocket = false;
  }
  double lo = xs.sb + 15.0, hi = xs.se - 15.0;
  if (xs.side[0].pocket) hi = std::min(hi, xs.side[0].pocket_start - 5.0);
  if (xs.side[1].pocket) lo = std::max(lo, xs.side[1].pocket_start + 5.0);
  if (!isMajor(cls)) return;
  for (int k = 0; k < 2; ++k) {
    Side& sd = xs.side[k];
    if (sd.dir == 0 || sd.edge != Edge::kNone || hi - lo < kBayLength) continue;
    if (!chance(r, o_.p_bus_bay)) continue;
    sd.bay = true;
    sd.bay_s0 = uni(r, lo, hi - kBayLength);
    sd.bay_s1 = sd.bay_s0 + kBayLength;
    sd.bay_w = uni(r, 2.8, 3.2);
    // The other side's bay must not share the range (keeps sections simple).
    if (k == 0) {
      if (sd.bay_s0 - lo > hi - sd.bay_s1) hi = sd.bay_s0 - 5.0;
      else lo = sd.bay_s1 + 5.0;
    }
  }
}

void Builder::fillColumns(const CrossSection& xs, Section& sec) const {
  sec.cols = columnTemplate(xs, sec);
  sec.ss = xs.line.samplesBetween(sec.s0, sec.s1);
  sec.d.assign(sec.cols.size(), std::vector<double>(sec.ss.size()));
  for (size_t i = 0; i < sec.ss.size(); ++i) {
    const auto v = columnValues(xs, sec, sec.ss[i]);
    for (size_t c = 0; c < v.size(); ++c) sec.d[c][i] = v[c];
  }
}

std::vector<Vector3d> Builder::boundaryPoints(const CrossSection& xs, const Section& sec, int col) const {
  // The inner edge of a bend tighter than the offset folds: it is a corner on the ground.
  auto pts = columnPoints3(xs, sec, col);
  std::vector<Vector2d> dirs(sec.ss.size());
  for (size_t i = 0; i < dirs.size(); ++i) dirs[i] = xs.line.tangentAt(sec.ss[i]);
  geom::dropBackwardPoints(pts, dirs);
  geom::removeLoops(pts, 80);
  return pts;
}

std::vector<std::pair<int, int>> Builder::laneColumns(const Section& sec, int k) const {
  const int nc = static_cast<int>(sec.cols.size());
  int anchor = -1;
  for (int c = 0; c < nc; ++c) {
    if (sec.cols[c].kind == ColKind::kAnchor) anchor = c;
  }
  std::vector<std::pair<int, int>> out;
  int inner = anchor;
  for (int c = k == 0 ? anchor + 1 : anchor - 1; k == 0 ? c < nc : c >= 0; c += k == 0 ? 1 : -1) {
    if (sec.cols[c].kind == ColKind::kPocketDiv || sec.cols[c].kind == ColKind::kLaneOuter) out.emplace_back(inner, c);
    inner = c;
  }
  return out;
}

bool Builder::sectionIsSound(const CrossSection& xs, Section sec) const {
  fillColumns(xs, sec);
  for (int k = 0; k < 2; ++k) {
    if (xs.side[k].dir == 0) continue;
    for (const auto& [inner, outer] : laneColumns(sec, k)) {
      LineString in, out;
      in.points = boundaryPoints(xs, sec, inner);
      out.points = boundaryPoints(xs, sec, outer);
      Lanelet l;
      for (size_t i = 0; i < sec.ss.size(); ++i) {
        const Vector2d p = at(xs, sec.ss[i], (sec.d[inner][i] + sec.d[outer][i]) / 2.0);
        l.centre.emplace_back(p.x(), p.y(), 0.0);
      }
      if (xs.side[k].dir < 0) std::reverse(l.centre.begin(), l.centre.end());
      const bool left_is_inner = o_.right_hand_traffic;
      if (!lanelet2ReadsAsMeant(l, left_is_inner ? in : out, left_is_inner ? out : in)) return false;
    }
  }
  return true;
}

double Builder::halfTurn(const CrossSection& xs, double s0, double s1) const {
  constexpr double kStep = 1.0;
  std::vector<std::pair<double, double>> turned;  // (s, heading change from s0 to s)
  double total = 0.0;
  Vector2d previous = xs.line.tangentAt(s0);
  for (double s = s0 + kStep; s < s1; s += kStep) {
    const Vector2d t = xs.line.tangentAt(s);
    total += std::abs(intersections::headingChange(previous, t));
    previous = t;
    turned.emplace_back(s, total);
  }
  for (const auto& [s, sum] : turned) {
    if (sum >= total / 2.0) return s;
  }
  return (s0 + s1) / 2.0;
}

std::vector<Section> Builder::makeSections(const CrossSection& xs) const {
  std::vector<double> b = {xs.sb, xs.se};
  const Side& f = xs.side[0];
  const Side& g = xs.side[1];
  if (f.pocket) b.push_back(f.pocket_start);
  if (g.pocket) b.push_back(g.pocket_start);
  for (int k = 0; k < 2; ++k) {
    if (xs.side[k].bay) {
      b.push_back(xs.side[k].bay_s0);
      b.push_back(xs.side[k].bay_s1);
    }
  }
  std::sort(b.begin(), b.end());
  // The lanelet that splits at a pocket must not start at the intersection (it would merge and
  // diverge): give it a section of its own.
  if (f.pocket) {
    auto it = std::lower_bound(b.begin(), b.end(), f.pocket_start - 1e-6);
    if (it != b.begin() && std::abs(*(it - 1) - xs.sb) < 1e-6) b.push_back((xs.sb + f.pocket_start) / 2.0);
  }
  if (g.pocket) {
    auto it = std::upper_bound(b.begin(), b.end(), g.pocket_start + 1e-6);
    if (it != b.end() && std::abs(*it - xs.se) < 1e-6) b.push_back((xs.se + g.pocket_start) / 2.0);
  }
  std::sort(b.begin(), b.end());
  const auto section = [&](double s0, double s1) {
    Section sec;
    sec.s0 = s0;
    sec.s1 = s1;
    const double mid = (sec.s0 + sec.s1) / 2.0;
    sec.pocket_in[0] = f.pocket && mid > f.pocket_start;
    sec.pocket_in[1] = g.pocket && mid < g.pocket_start;
    for (int k = 0; k < 2; ++k) {
      const Side& sd = xs.side[k];
      sec.bay_in[k] = sd.bay && mid > sd.bay_s0 && mid < sd.bay_s1;
    }
    return sec;
  };
  std::vector<Section> out;
  for (size_t i = 0; i + 1 < b.size(); ++i) {
    if (b[i + 1] - b[i] >= 0.01) out.push_back(section(b[i], b[i + 1]));
  }
  // A long lanelet that turns back on itself (a hairpin) is read backwards by Lanelet2's loader
  // (its geometry::align compares the bounds' middle points): a section with such a lanelet is
  // split at the tip of its turn, up to three times over, while the pieces stay kMinPiece long.
  constexpr double kMinPiece = 5.0;
  for (int round = 0; round < 3; ++round) {
    std::vector<Section> next;
    bool split = false;
    for (const Section& sec : out) {
      const double s = halfTurn(xs, sec.s0, sec.s1);
      if (s - sec.s0 < kMinPiece || sec.s1 - s < kMinPiece || sectionIsSound(xs, sec)) {
        next.push_back(sec);
        continue;
      }
      next.push_back(section(sec.s0, s));
      next.push_back(section(s, sec.s1));
      split = true;
    }
    out = std::move(next);
    if (!split) break;
  }
  if (out.empty()) {  // cannot happen (se - sb >= 0.05), but never leave a road without lanes
    Section sec;
    sec.s0 = xs.sb;
    sec.s1 = xs.se;
    out.push_back(sec);
  }
  return out;
}

int Builder::edgeColumn(const Section& sec, int k, bool with_sidewalk) const {
  const int n = static_cast<int>(sec.cols.size());
  int anchor = -1;
  for (int i = 0; i < n; ++i) {
    if (sec.cols[i].kind == ColKind::kAnchor) anchor = i;
  }
  auto ok = [&](int i) {
    return sec.cols[i].side == k && (with_sidewalk || sec.cols[i].kind != ColKind::kSidewalkOuter);
  };
  if (k == 1) {
    for (int i = 0; i < anchor; ++i) {
      if (ok(i)) return i;
    }
  } else {
    for (int i = n - 1; i > anchor; --i) {
      if (ok(i)) return i;
    }
  }
  return anchor;
}

Vector2d Builder::at(const CrossSection& xs, double s, double canonical_d) const {
  return xs.line.offsetPoint(s, m_ * canonical_d);
}

double Builder::profileForColumn(const CrossSection& xs, const Section& sec, size_t i, double dcan) const {
  const double l = m_ * sec.d[curbColumn(sec, 1)][i];
  const double r = m_ * sec.d[curbColumn(sec, 0)][i];
  return profileAt(xs, sec.ss[i], m_ * dcan, std::max(l, r), std::min(l, r));
}

std::vector<Vector2d> Builder::columnPoints(const CrossSection& xs, const Section& sec, int col) const {
  std::vector<Vector2d> pts(sec.ss.size());
  for (size_t i = 0; i < sec.ss.size(); ++i) pts[i] = at(xs, sec.ss[i], sec.d[col][i]);
  return pts;
}

std::vector<Vector3d> Builder::columnPoints3(const CrossSection& xs, const Section& sec, int col) const {
  std::vector<Vector3d> pts(sec.ss.size());
  for (size_t i = 0; i < sec.ss.size(); ++i) {
    const Vector2d p = at(xs, sec.ss[i], sec.d[col][i]);
    pts[i] = Vector3d(p.x(), p.y(), terrainAt(p) + profileForColumn(xs, sec, i, sec.d[col][i]));
  }
  return pts;
}

void Builder::buildCrossSection(CrossSection& xs) {
  chooseTrim(xs);
  choosePocketsAndBays(xs);
  xs.sections = makeSections(xs);
  for (int k = 0; k < 2; ++k) {
    if (xs.side[k].bay) ++impl_->stats.bus_bays;
    if (xs.side[k].edge == Edge::kParking) ++impl_->stats.parking_lanes;
    if (xs.side[k].edge == Edge::kBike) ++impl_->stats.bike_lanes;
  }
  xs.left_extent = 0.0;
  xs.right_extent = 0.0;
  for (auto& sec : xs.sections) buildSection(xs, sec);
  linkSections(xs);
  buildEnds(xs);
  ++impl_->stats.cross_sections;
}

void Builder::buildSection(CrossSection& xs, Section& sec) {
  fillColumns(xs, sec);
  const int nc = static_cast<int>(sec.cols.size());
  for (int c = 0; c < nc; ++c) {
    for (double v : sec.d[c]) {
      xs.left_extent = std::max(xs.left_extent, m_ * v);
      xs.right_extent = std::min(xs.right_extent, m_ * v);
    }
  }
  // 1. LineStrings.
  sec.line_ids.assign(nc, 0);
  for (int c = 0; c < nc; ++c) {
    const LineType type = lineTypeOf(xs, sec, sec.cols[c]);
    if (sec.cols[c].kind == ColKind::kSidewalkOuter) continue;
    LineString ls;
    ls.id = nextId();
    ls.type = type;
    ls.points = boundaryPoints(xs, sec, c);
    // Lines inside the backward side run in its driving direction; the anchor and the forward
    // side run along the reference (the centre line is the one shared, inverted for one side).
    const bool reversed = sec.cols[c].side == 1 && xs.side[1].dir != 0;
    if (reversed) std::reverse(ls.points.begin(), ls.points.end());
    sec.line_ids[c] = ls.id;
    // Paint.
    std::vector<Vector2d> p2(ls.points.size());
    for (size_t i = 0; i < p2.size(); ++i) p2[i] = ls.points[i].head<2>();
    const double len = geom::polylineLength(p2);
    auto gaps = chooseGaps(ls.id, type, len);
    for (const auto& g : gaps) {
      impl_->gaps.push_back(g);
      ++(g.missing ? impl_->stats.missing : impl_->stats.faded);
    }
    // Outward (for the curb band) relative to the line's own left normal.
    const int col_side = sec.cols[c].side;
    double canon_out = col_side == 1 ? +1.0 : -1.0;
    if (col_side == -1) canon_out = +1.0;  // one-way anchor curb: the left edge
    double outward = canon_out * m_;
    if (reversed) outward = -outward;
    emitLinePaint(p2, type, outward, gaps);
    pushLine(std::move(ls));
  }
  // 2. Strips: lanes (lanelets), shoulders, sidewalks.
  int anchor = -1;
  for (int c = 0; c < nc; ++c) {
    if (sec.cols[c].kind == ColKind::kAnchor) anchor = c;
  }
  for (int k = 0; k < 2; ++k) {
    const Side& sd = xs.side[k];
    // Columns of this side, inner -> outer, with the inner neighbour of each.
    std::vector<int> chain;
    if (k == 0) {
      for (int c = anchor + 1; c < nc; ++c) chain.push_back(c);
    } else {
      for (int c = anchor - 1; c >= 0; --c) chain.push_back(c);
    }
    int inner = anchor;
    std::vector<int64_t> lane_ids;
    int lane_count = 0;
    for (int c : chain) {
      if (sec.cols[c].kind == ColKind::kPocketDiv || sec.cols[c].kind == ColKind::kLaneOuter) ++lane_count;
    }
    int pos = 0;
    for (int c : chain) {
      const Column& col = sec.cols[c];
      auto poly = stripPolygon(xs, sec, inner, c);
      if (col.kind == ColKind::kPocketDiv || col.kind == ColKind::kLaneOuter) {
        const bool pocket = col.kind == ColKind::kPocketDiv;
        const int64_t id = makeRoadLanelet(xs, sec, k, inner, c, pos, lane_count, pocket);
        lane_ids.push_back(id);
        addFill(Surface::kAsphalt, detail::kLayerLane, std::move(poly), id);
        ++pos;
      } else if (col.kind == ColKind::kEdgeOuter) {
        const Surface s = sd.edge == Edge::kBike ? Surface::kBikeLane : Surface::kParking;
        addFill(s, detail::kLayerShoulder, std::move(poly));
      } else if (col.kind == ColKind::kSidewalkOuter) {
        addFill(Surface::kSidewalk, detail::kLayerSidewalk, std::move(poly));
      }
      inner = c;
    }
    sec.lanes[k] = lane_ids;
  }
  // 3. Road profile quads.
  const int cl = curbColumn(sec, 1), cr = curbColumn(sec, 0);
  const int ol = outerColumn(sec, 1), orr = outerColumn(sec, 0);
  for (size_t i = 0; i + 1 < sec.ss.size(); ++i) {
    detail::CrownQuad q;
    for (int e = 0; e < 2; ++e) {
      const size_t j = i + e;
      const double s = sec.ss[j];
      (e == 0 ? q.a : q.b) = xs.line.pointAt(s);
      (e == 0 ? q.na : q.nb) = xs.line.normalAt(s);
      const double a1 = m_ * sec.d[cl][j], a2 = m_ * sec.d[cr][j];
      q.left_curb[e] = std::max(a1, a2);
      q.right_curb[e] = std::min(a1, a2);
      const double b1 = m_ * sec.d[ol][j], b2 = m_ * sec.d[orr][j];
      q.left_outer[e] = std::max(b1, b2);
      q.right_outer[e] = std::min(b1, b2);
      q.fade[e] = geom::smoothstep(std::min(s - xs.sb, xs.se - s) / kCrownFadeM);
    }
    impl_->quads.push_back(q);
  }
}

int64_t Builder::makeRoadLanelet(const CrossSection& xs, const Section& sec, int k, int inner, int outer, int pos,
    int count, bool pocket) {
  const Side& sd = xs.side[k];
  Lanelet l;
  l.id = nextId();
  l.kind = LaneletKind::kRoad;
  const bool left_is_inner = o_.right_hand_traffic;
  const int left_col = left_is_inner ? inner : outer;
  const int right_col = left_is_inner ? outer : inner;
  l.left_id = sec.line_ids[left_col];
  l.right_id = sec.line_ids[right_col];
  for (size_t i = 0; i < sec.ss.size(); ++i) {
    const double dc = (sec.d[inner][i] + sec.d[outer][i]) / 2.0;
    const Vector2d p = at(xs, sec.ss[i], dc);
    l.centre.emplace_back(p.x(), p.y(), terrainAt(p) + profileForColumn(xs, sec, i, dc));
  }
  if (sd.dir < 0) std::reverse(l.centre.begin(), l.centre.end());
  l.road_id = sd.road_id;
  l.from_node = sd.from_node;
  l.to_node = sd.to_node;
  l.index_from_left = o_.right_hand_traffic ? pos : count - 1 - pos;
  detail::LaneSlot slot;
  slot.cross_section = xs.key;
  slot.dir = sd.dir;
  slot.rank_centre = pos;
  slot.rank_curb = count - 1 - pos;
  impl_->slots[l.id] = slot;
  lanelet_meta_[l.id] = {pocket, pos};
  const int64_t id = l.id;
  pushLanelet(std::move(l));
  ++impl_->stats.road_lanelets;
  return id;
}

void Builder::pushLanelet(Lanelet&& l) {
  lanelet_pos_[l.id] = truth().lanelets.size();
  truth().lanelets.push_back(std::move(l));
}

void Builder::pushLine(LineString&& l) {
  line_pos_[l.id] = truth().lines.size();
  truth().lines.push_back(std::move(l));
}

void Builder::linkSections(CrossSection& xs) {
  for (int k = 0; k < 2; ++k) {
    const Side& sd = xs.side[k];
    if (sd.dir == 0) continue;
    const int n = static_cast<int>(xs.sections.size());
    for (int q = 0; q + 1 < n; ++q) {
      const Section& a = sd.dir > 0 ? xs.sections[q] : xs.sections[q + 1];  // predecessor
      const Section& b = sd.dir > 0 ? xs.sections[q + 1] : xs.sections[q];  // successor
      const auto& la = a.lanes[k];
      const auto& lb = b.lanes[k];
      // Match by rank from the curb (pockets appear on the inner side).
      for (size_t i = 0; i < la.size(); ++i) {
        const size_t rank = la.size() - 1 - i;
        if (rank < lb.size()) laneletRef(la[i]).successors.push_back(lb[lb.size() - 1 - rank]);
      }
      if (lb.size() > la.size() && !la.empty()) {  // a pocket opens: the inner lane splits
        for (size_t j = 0; j + la.size() < lb.size(); ++j) laneletRef(la.front()).successors.push_back(lb[j]);
      }
    }
  }
}

void Builder::buildEnds(CrossSection& xs) {
  auto r = rngFor(o_.seed, xs.ref->id, 5);
  for (int k = 0; k < 2; ++k) {
    const Side& sd = xs.side[k];
    if (sd.dir == 0) continue;
    // Approach: the last section in the driving direction; departure: the first.
    const Section& last = sd.dir > 0 ? xs.sections.back() : xs.sections.front();
    const Section& first = sd.dir > 0 ? xs.sections.front() : xs.sections.back();
    incoming_[sd.to_node].push_back(laneEnds(xs, last, k, true));
    outgoing_[sd.from_node].push_back(laneEnds(xs, first, k, false));
  }
  // Crosswalks at each end; stop lines for the approaches.
  for (int end = 0; end < 2; ++end) {
    const int64_t node = end == 0 ? xs.ref->from : xs.ref->to;
    const double e = end == 0 ? xs.sb : xs.se;
    const double inward = end == 0 ? +1.0 : -1.0;  // towards the road's middle, in s
    const Vector2d ep = xs.line.pointAt(e);
    end_points_[node].push_back(ep);
    const Section& sec = end == 0 ? xs.sections.front() : xs.sections.back();
    for (int k = 0; k < 2; ++k) {
      const int c = curbColumn(sec, k);
      const size_t i = end == 0 ? 0 : sec.ss.size() - 1;
      end_points_[node].push_back(at(xs, sec.ss[i], sec.d[c][i]));
    }
    if (degree(node) < 3) continue;
    bool crosswalk = false;
    if (xs.se - xs.sb >= 20.0 && chance(r, o_.p_crosswalk)) {
      const double a = e + inward * kCrosswalkSetback, b = e + inward * (kCrosswalkSetback + kCrosswalkDepth);
      const Section* s = sectionContaining(xs, std::min(a, b), std::max(a, b));
      if (s) {
        emitCrosswalk(xs, *s, std::min(a, b), std::max(a, b));
        crosswalk = true;
        ++impl_->stats.crosswalks;
      }
    }
    // The side approaching this end: forward side approaches `to` (end 1), backward `from`.
    const int k = end == 1 ? 0 : 1;
    const Side& sd = xs.side[k];
    if (sd.dir == 0 || sd.to_node != node || xs.se - xs.sb < 10.0 || !chance(r, o_.p_stop_line)) continue;
    const double s_stop = e + inward * (crosswalk ? kCrosswalkSetback + kCrosswalkDepth + 1.0 : 1.0);
    const Section* s = sectionContaining(xs, s_stop - kStopLineWidth, s_stop + kStopLineWidth);
    if (!s) continue;
    emitStopLine(xs, *s, k, s_stop);
  }
}

const Section* Builder::sectionContaining(const CrossSection& xs, double a, double b) const {
  for (const auto& s : xs.sections) {
    if (a >= s.s0 - 1e-9 && b <= s.s1 + 1e-9) return &s;
  }
  return nullptr;
}

Approach Builder::laneEnds(const CrossSection& xs, const Section& sec, int k, bool at_end) {
  const Side& sd = xs.side[k];
  Approach ap;
  ap.road_id = sd.road_id;
  ap.xs = xs.key;
  // Sample index of this end: the driving direction's end (approach) or start (departure).
  const bool ref_end = (sd.dir > 0) == at_end;
  const size_t i = ref_end ? sec.ss.size() - 1 : 0;
  const double s = sec.ss[i];
  Vector2d t = xs.line.tangentAt(s) * static_cast<double>(sd.dir);
  for (int64_t id : sec.lanes[k]) {
    const Lanelet& l = laneletRef(id);
    const LineString& lb = lineRef(l.left_id);
    const LineString& rb = lineRef(l.right_id);
    LaneEnd le;
    le.lanelet = id;
    le.centre = (at_end ? l.centre.back() : l.centre.front()).head<2>();
    // Bound points at this end: the bound stored along the driving direction or not.
    auto endOf = [&](const LineString& ls) {
      const Vector2d a = ls.points.front().head<2>(), b = ls.points.back().head<2>();
      return (a - le.centre).norm() < (b - le.centre).norm() ? a : b;
    };
    le.left = endOf(lb);
    le.right = endOf(rb);
    le.width = (le.left - le.right).norm();
    le.tangent = t;
    le.pocket = lanelet_meta_[id].first;
    const int idx = l.index_from_left;
    ap.lanes.resize(std::max<size_t>(ap.lanes.size(), idx + 1));
    ap.lanes[idx] = le;
  }
  // turn:lanes movements (for approaches): the non-pocket lanes in order.
  if (at_end) {
    std::vector<int> regular;
    for (size_t j = 0; j < ap.lanes.size(); ++j) {
      if (!ap.lanes[j].pocket) regular.push_back(static_cast<int>(j));
    }
    // sd.turn is inner -> outer; map to left -> right.
    std::vector<std::string> lr = sd.turn;
    if (!o_.right_hand_traffic) std::reverse(lr.begin(), lr.end());
    if (lr.size() == regular.size()) {
      for (size_t j = 0; j < regular.size(); ++j) ap.lanes[regular[j]].moves = osm::parseTurnLane(lr[j]);
    }
    for (auto& le : ap.lanes) {
      if (le.pocket) {
        le.moves.specified = true;
        le.moves.left = o_.right_hand_traffic;
        le.moves.right = !o_.right_hand_traffic;
      }
    }
  }
  return ap;
}

}  // namespace lanemap::sim::world_build
