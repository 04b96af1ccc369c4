// let_harness: reference LET-3D-AP numbers from Waymo Open Dataset's own C++
// metrics code (metrics/{iou,matcher,detection_metrics}.cc, unmodified).
//
// Usage: let_harness INPUT.json OUTPUT.json (the formats: scripts/let_reference_cases.py writes
// INPUT and reads OUTPUT; docs/metrics.md, "LET-3D-AP"). Built by build.sh beside it, outside
// stereodet's build.
#include <glog/logging.h>

#include <fstream>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <numeric>
#include <string>
#include <vector>

#include "waymo_open_dataset/label.pb.h"
#include "waymo_open_dataset/metrics/detection_metrics.h"
#include "waymo_open_dataset/metrics/iou.h"
#include "waymo_open_dataset/metrics/matcher.h"
#include "waymo_open_dataset/protos/breakdown.pb.h"
#include "waymo_open_dataset/protos/metrics.pb.h"

namespace wod = waymo::open_dataset;
using json = nlohmann::json;
using LetConfig = wod::Config::LongitudinalErrorTolerantConfig;

namespace {

[[noreturn]] void Die(const std::string& msg) {
  std::cerr << "let_harness: " << msg << std::endl;
  std::exit(2);
}

wod::Label::Box ToBox(const json& a, size_t min_len) {
  if (!a.is_array() || a.size() < min_len) Die("bad box: " + a.dump());
  wod::Label::Box b;
  b.set_center_x(a[0].get<double>());
  b.set_center_y(a[1].get<double>());
  b.set_center_z(a[2].get<double>());
  b.set_length(a[3].get<double>());
  b.set_width(a[4].get<double>());
  b.set_height(a[5].get<double>());
  b.set_heading(a[6].get<double>());
  return b;
}

LetConfig::AlignType ParseAlign(const std::string& s) {
  if (s == "range") return LetConfig::TYPE_RANGE_ALIGNED;
  if (s == "none") return LetConfig::TYPE_NOT_ALIGNED;
  if (s == "center") return LetConfig::TYPE_CENTER_ALIGNED;
  if (s == "further_only") return LetConfig::TYPE_FURTHER_ONLY_RANGE_ALIGNED;
  if (s == "any_closer_only") return LetConfig::TYPE_ANY_CLOSER_ONLY_RANGE_ALIGNED;
  if (s == "between_origin_and_gt_only")
    return LetConfig::TYPE_BETWEEN_ORIGIN_AND_GT_ONLY_RANGE_ALIGNED;
  Die("unknown let.align: " + s);
}

}  // namespace

int main(int argc, char** argv) {
  google::InitGoogleLogging(argv[0]);
  FLAGS_logtostderr = true;
  if (argc != 3) Die("usage: let_harness INPUT.json OUTPUT.json");
  std::ifstream in(argv[1]);
  if (!in) Die(std::string("cannot open ") + argv[1]);
  const json input = json::parse(in);

  // ---------------------------------------------------------------- Config.
  wod::Config config;
  // One breakdown: OBJECT_TYPE (shard TYPE_VEHICLE-1 = 0 is the vehicle
  // result), one difficulty level: LEVEL_1.
  config.add_breakdown_generator_ids(wod::Breakdown::OBJECT_TYPE);
  config.add_difficulties()->add_levels(wod::Label::LEVEL_1);

  const std::string matcher = input.value("matcher", std::string("hungarian"));
  if (matcher == "hungarian") {
    config.set_matcher_type(wod::MatcherProto::TYPE_HUNGARIAN);
  } else if (matcher == "score_first") {
    config.set_matcher_type(wod::MatcherProto::TYPE_SCORE_FIRST);
  } else {
    Die("unknown matcher: " + matcher);
  }

  const std::string box_type_s = input.value("box_type", std::string("3d"));
  wod::Label::Box::Type box_type;
  if (box_type_s == "3d") {
    box_type = wod::Label::Box::TYPE_3D;
  } else if (box_type_s == "bev") {
    box_type = wod::Label::Box::TYPE_2D;
  } else {
    Die("unknown box_type: " + box_type_s);
  }
  config.set_box_type(box_type);

  // iou_thresholds indexed by Label::Type (size Type_MAX + 1).
  const float iou_threshold = input.at("iou_threshold").get<double>();
  for (int t = 0; t <= wod::Label::Type_MAX; ++t) {
    config.add_iou_thresholds(t == wod::Label::TYPE_VEHICLE ? iou_threshold : 0.5f);
  }

  if (input.contains("score_cutoffs")) {
    for (const auto& s : input["score_cutoffs"]) {
      config.add_score_cutoffs(s.get<double>());
    }
  } else {
    for (int i = 0; i < 100; ++i) config.add_score_cutoffs(i * 0.01);
  }
  if (config.score_cutoffs_size() == 0) Die("empty score_cutoffs");

  config.set_desired_recall_delta(0.05);
  config.set_min_precision(0.0);
  // The TP test in detection_metrics.cc is
  //   if (heading_accuracy <= min_heading_accuracy) continue;
  // and heading_accuracy is in [0, 1], so -1 (the proto default) never gates.
  config.set_min_heading_accuracy(-1.0);

  const json let = input.value("let", json::object());
  LetConfig* let_cfg = config.mutable_let_metric_config();
  let_cfg->set_enabled(let.value("enabled", false));
  let_cfg->set_longitudinal_tolerance_percentage(let.value("percentage", 0.1));
  let_cfg->set_min_longitudinal_tolerance_meter(let.value("min_meter", 0.5));
  const json sensor = let.value("sensor", json::array({0.0, 0.0, 0.0}));
  let_cfg->mutable_sensor_location()->set_x(sensor.at(0).get<double>());
  let_cfg->mutable_sensor_location()->set_y(sensor.at(1).get<double>());
  let_cfg->mutable_sensor_location()->set_z(sensor.at(2).get<double>());
  let_cfg->set_align_type(ParseAlign(let.value("align", std::string("range"))));

  // ---------------------------------------------------------------- Objects.
  std::vector<std::vector<wod::Object>> pds_frames, gts_frames;
  for (const auto& frame : input.at("frames")) {
    std::vector<wod::Object> gts, pds;
    int k = 0;
    for (const auto& g : frame.value("gts", json::array())) {
      wod::Object o;
      *o.mutable_object()->mutable_box() = ToBox(g, 7);
      o.mutable_object()->set_type(wod::Label::TYPE_VEHICLE);
      o.mutable_object()->set_detection_difficulty_level(wod::Label::LEVEL_1);
      o.mutable_object()->set_id("gt" + std::to_string(k++));
      gts.push_back(o);
    }
    k = 0;
    for (const auto& p : frame.value("pds", json::array())) {
      wod::Object o;
      *o.mutable_object()->mutable_box() = ToBox(p, 8);
      o.mutable_object()->set_type(wod::Label::TYPE_VEHICLE);
      o.mutable_object()->set_id("pd" + std::to_string(k++));
      o.set_score(p[7].get<double>());
      pds.push_back(o);
    }
    gts_frames.push_back(std::move(gts));
    pds_frames.push_back(std::move(pds));
  }

  json out;
  out["let_iou"] = json::array();
  out["affinity"] = json::array();
  out["matches"] = json::array();

  // --------------------------------------------- Per-pair values, matching.
  std::vector<std::vector<wod::DetectionMeasurements>> measurements;
  for (size_t f = 0; f < gts_frames.size(); ++f) {
    const auto& gts = gts_frames[f];
    const auto& pds = pds_frames[f];
    json ious = json::array(), affs = json::array();
    for (const auto& p : pds) {
      json iou_row = json::array(), aff_row = json::array();
      for (const auto& g : gts) {
        const auto& pb = p.object().box();
        const auto& gb = g.object().box();
        iou_row.push_back(let_cfg->enabled()
                              ? wod::ComputeLetIoU(pb, gb, let_cfg->sensor_location(),
                                                   let_cfg->align_type(), box_type)
                              : wod::ComputeIoU(pb, gb, box_type));
        aff_row.push_back(wod::ComputeLongitudinalAffinity(pb, gb, *let_cfg));
      }
      ious.push_back(iou_row);
      affs.push_back(aff_row);
    }
    out["let_iou"].push_back(ious);
    out["affinity"].push_back(affs);

    // Matcher created exactly as ComputeDetectionMeasurements does
    // (Matcher::Create(config) installs the LET IoU / affinity / CanMatch /
    // weight functions when let is enabled). All predictions, all gts.
    std::unique_ptr<wod::Matcher> m = wod::Matcher::Create(config);
    m->SetGroundTruths(gts);
    m->SetPredictions(pds);
    std::vector<int> pd_subset(pds.size()), gt_subset(gts.size());
    std::iota(pd_subset.begin(), pd_subset.end(), 0);
    std::iota(gt_subset.begin(), gt_subset.end(), 0);
    m->SetPredictionSubset(pd_subset);
    m->SetGroundTruthSubset(gt_subset);
    std::vector<int> pd_matches, gt_matches;
    m->Match(&pd_matches, &gt_matches);
    json mrow = json::array();
    for (int i = 0; i < static_cast<int>(pds.size()); ++i) {
      mrow.push_back(pd_matches[i] >= 0 ? gt_subset[pd_matches[i]] : -1);
    }
    out["matches"].push_back(mrow);

    measurements.push_back(wod::ComputeDetectionMeasurements(config, pds, gts));
  }

  // ---------------------------------------------------------------- Metrics.
  const std::vector<wod::DetectionMetrics> metrics =
      wod::ComputeDetectionMetrics(config, measurements);
  const wod::DetectionMetrics* veh = nullptr;
  for (const auto& mt : metrics) {
    if (mt.breakdown().generator_id() == wod::Breakdown::OBJECT_TYPE &&
        mt.breakdown().shard() == wod::Label::TYPE_VEHICLE - 1 &&
        mt.breakdown().difficulty_level() == wod::Label::LEVEL_1) {
      veh = &mt;
    }
  }
  if (veh == nullptr) Die("no vehicle/LEVEL_1 result (no frames?)");

  out["cutoffs"] = json::array();
  for (const auto& ms : veh->measurements().measurements()) {
    out["cutoffs"].push_back({{"score_cutoff", ms.score_cutoff()},
                              {"num_tps", ms.num_tps()},
                              {"num_fps", ms.num_fps()},
                              {"num_fns", ms.num_fns()},
                              {"sum_longitudinal_affinity", ms.sum_longitudinal_affinity()},
                              {"sum_ha", ms.sum_ha()}});
  }
  out["ap"] = veh->mean_average_precision();
  out["apl"] = veh->mean_average_precision_longitudinal_affinity_weighted();
  out["aph"] = veh->mean_average_precision_ha_weighted();
  out["precisions"] = std::vector<float>(veh->precisions().begin(), veh->precisions().end());
  out["recalls"] = std::vector<float>(veh->recalls().begin(), veh->recalls().end());
  out["precisions_longitudinal_affinity_weighted"] =
      std::vector<float>(veh->precisions_longitudinal_affinity_weighted().begin(),
                         veh->precisions_longitudinal_affinity_weighted().end());
  out["precisions_ha_weighted"] = std::vector<float>(veh->precisions_ha_weighted().begin(),
                                                     veh->precisions_ha_weighted().end());
  out["config"] = config.ShortDebugString();

  std::ofstream o(argv[2]);
  if (!o) Die(std::string("cannot write ") + argv[2]);
  o << out.dump(1) << "\n";
  return 0;
}
