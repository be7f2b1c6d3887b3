// geojcbb_qemu: the firmware on an emulated Cortex-M4F. Starts QEMU (mps2-an386) with the firmware
// ELF halted, finds the UART's pty through QMP, opens it, lets the CPU run, handshakes and streams a
// simulated scenario (or, with --log, a recorded log: its first --seconds) for each strategy,
// printing the same score table as the desktop loop (geojcbb_link). With --submaps the firmware's
// local maps are handed over the link and joined on the host (docs/submaps.md). With --check every ASSOC_RESULT and POSE is compared, bit for bit, with the same
// node running in float in this process; with --budget each scan's instruction counts (STATS under
// -icount) are collected and summarised. Ends with SHUTDOWN: the firmware exits QEMU through
// semihosting with status 0.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "geojcbb_host/event_log.hpp"
#include "geojcbb_host/mirror.hpp"
#include "geojcbb_host/qemu.hpp"
#include "geojcbb_host/run_cli.hpp"
#include "geojcbb_host/stream.hpp"
#include "geojcbb_host/guarded_main.hpp"

using namespace geojcbb;
using namespace geojcbb::host;

namespace {

struct Budget {
  std::vector<std::uint32_t> associate, step, observations;
  std::vector<std::uint32_t> predict_local, update, augment_review;  ///< the step's other stages (CSV only)
  std::vector<std::uint32_t> associate20;  ///< association of scans with at least 20 observations
  std::vector<std::uint32_t> budget_hit;   ///< association of scans that hit the JCBB node budget
  std::vector<std::uint32_t> relocalise;   ///< the relocaliser's alignment, of the scans that ran it
  std::vector<std::uint32_t> loop;         ///< the loop-closure check, of the scans that ran it
  std::vector<std::uint32_t> window;       ///< clusters first and the hypothesis window, of the scans that ran them
  std::vector<std::uint32_t> lost_test;    ///< the lost test, per scan (0: not run)
  std::vector<std::uint32_t> score;        ///< the posterior scoring (inside the rows above), per scan
  std::vector<std::uint32_t> existence;    ///< the landmarks' existence update (inside augment_review), per scan
  std::vector<std::uint32_t> map_worst;    ///< per local map (--submaps): its scans' largest step
  std::uint32_t hits_before = 0;           ///< the device's budget_hits counter before the scan
  bool started = false;
  bool map_open = false;
};

/// The first `seconds` of a recorded run (all of it for 0).
class FirstSeconds : public RecordedSource {
 public:
  FirstSeconds(RunSource& src, double seconds) : RecordedSource(src) {
    if (seconds <= 0 || inputs_.empty()) return;
    const double end = inputs_.front().t_s + seconds;
    inputs_.erase(std::find_if(inputs_.begin(), inputs_.end(), [&](const RunInput& in) { return in.t_s > end; }),
                  inputs_.end());
  }
};

std::uint32_t median(std::vector<std::uint32_t> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}
std::uint32_t maximum(const std::vector<std::uint32_t>& v) {
  return v.empty() ? 0 : *std::max_element(v.begin(), v.end());
}

template <class B>
bool matches(const proto::Capabilities& c) {
  return c.max_observations == B::kMaxObservations && c.max_candidates == B::kMaxCandidates &&
         c.max_groups == B::kMaxGroups && c.max_landmarks == B::kMaxLandmarks && c.max_jcbb_nodes == B::kMaxJcbbNodes;
}

// One strategy over the link, optionally mirrored by the in-process node with bounds B.
template <class B>
RunResult run_one(Transport& port, RunSource& src, const RunOptions& o, bool check, bool budget, int timeout_ms,
                  MirrorReport& mirror_report, Budget& b) {
  std::unique_ptr<MirrorTransport<B>> mirror;
  if (check) mirror = std::make_unique<MirrorTransport<B>>(port);
  Transport& t = check ? static_cast<Transport&>(*mirror) : port;
  LinkClient link(t, timeout_ms);
  link.hello();  // the client learns the device's capacity; the mirror's node gets its HELLO too
  ScanHook hook = nullptr;
  if (budget) {
    hook = [&](const LinkObsBatch& batch, const LinkClient::ScanReply& reply) {
      const proto::Stats st = link.stats();
      if (!b.map_open) b.map_worst.push_back(0);
      b.map_worst.back() = std::max(b.map_worst.back(), st.instr_step);
      b.map_open = reply.pose.submap_frames == 0;  // the map closed with this scan
      b.associate.push_back(st.instr_associate);
      b.step.push_back(st.instr_step);
      b.predict_local.push_back(st.instr_predict_local);
      b.update.push_back(st.instr_update);
      b.augment_review.push_back(st.instr_augment_review);
      if (st.instr_relocalise > 0) b.relocalise.push_back(st.instr_relocalise);
      if (st.instr_loop > 0) b.loop.push_back(st.instr_loop);
      if (st.instr_window > 0) b.window.push_back(st.instr_window);
      b.lost_test.push_back(st.instr_lost_test);
      b.score.push_back(st.instr_score);
      b.existence.push_back(st.instr_existence);
      b.observations.push_back(batch.count);
      if (batch.count >= 20) b.associate20.push_back(st.instr_associate);
      if (b.started && st.budget_hits > b.hits_before) b.budget_hit.push_back(st.instr_associate);
      b.hits_before = st.budget_hits;
      b.started = true;
    };
  }
  PlainLink pl(link);
  StreamOptions so;
  so.hook = hook;
  src.rewind();
  RunResult r = stream_run(pl, src, o, so);
  if (mirror) mirror_report = mirror->report();
  return r;
}

// A fully ambiguous scan: a first scan maps one landmark per observation, then the same
// observations arrive with a covariance so wide (sigma 20 m, 1 rad) that every observation is
// individually compatible with every landmark: the most expensive gating and grouping, and the
// widest JCBB tree (which its bound still prunes: no such scan reached the node budget).
void worst_case(Transport& port, const proto::Capabilities& caps, const std::vector<Method>& methods, int scans,
                int timeout_ms, NodeCount node_budget) {
  const NodeCount budget = node_budget > 0 ? node_budget : caps.max_jcbb_nodes;
  std::printf("worst case: %u observations, each compatible with each of %u landmarks; node budget %u\n",
              caps.max_observations, caps.max_observations, budget);
  std::printf("  %-8s %6s %12s %14s %14s %14s\n", "strategy", "scans", "budget hits", "assoc median", "assoc max",
              "step max");
  const std::size_t m = std::min<std::size_t>(caps.max_observations, kLinkMaxObs);
  for (const Method& method : methods) {
    LinkClient link(port, timeout_ms);
    link.hello();
    proto::Config c;
    c.strategy = static_cast<proto::StrategyCode>(method.strategy);
    c.verify = method.verify;
    c.local_radius_m = 40.0f;
    c.max_range_m = 30.0f;
    c.node_budget = budget;
    c.landmark_delete_nats = -1e5f;  // nothing removed: the map grows to the bound
    c.max_tentative_reviews = 255;
    link.configure(c);
    proto::Reset r;
    r.cov_upper = {1e-6f, 0.0f, 0.0f, 1e-6f, 0.0f, 1e-6f};
    link.reset(r);
    LinkObsBatch b;
    b.count = static_cast<std::uint8_t>(m);
    for (std::size_t i = 0; i < m; ++i) {
      const float bearing = -1.2f + 2.4f * static_cast<float>(i) / static_cast<float>(m);
      b.obs[i] = proto::ObservationWire{10.0f + 0.3f * static_cast<float>(i), bearing, 0.01f, 0.0f, 1e-4f};
    }
    b.batch_id = 0;
    link.scan(b);  // maps them
    const std::uint32_t hits0 = link.stats().budget_hits;
    std::vector<std::uint32_t> assoc, step;
    for (std::size_t i = 0; i < m; ++i) {
      b.obs[i].r00 = 400.0f;
      b.obs[i].r11 = 1.0f;
    }
    for (int k = 1; k <= scans; ++k) {
      b.batch_id = static_cast<std::uint32_t>(k);
      link.scan(b);
      const proto::Stats st = link.stats();
      assoc.push_back(st.instr_associate);
      step.push_back(st.instr_step);
    }
    const std::uint32_t hits = link.stats().budget_hits - hits0;
    std::printf("  %-8s %6d %12u %14u %14u %14u\n", method.name().c_str(), scans, hits, median(assoc), maximum(assoc),
                maximum(step));
  }
}

}  // namespace

namespace {

// geojcbb_qemu's command line.
struct QemuCli {
  QemuOptions q;
  std::string scenario = std::string(GEOJCBB_SCENARIO_DIR) + "/env1.json", budget_csv;
  std::vector<std::string> names;
  std::uint64_t seed = 1;
  int timeout_ms = 20000;
  bool check = false, budget = false;
  int worst = 0;
  RunOptions o;
  std::string log_path;
  double seconds = 0;
};

void add_options(CLI::App& app, QemuCli& c) {
  app.add_option("--elf", c.q.elf, "firmware image")->default_val(c.q.elf);
  app.add_option("--qemu", c.q.qemu, "QEMU program")->default_val(c.q.qemu);
  app.add_option("--machine", c.q.machine, "QEMU machine: mps2-an386 or netduinoplus2 (the ELF must be built for it)")
      ->default_val(c.q.machine);
  app.add_option("--scenario", c.scenario, "scenario JSON file")->default_val(c.scenario);
  app.add_option("--log", c.log_path,
                 "instead of a scenario: a recorded log (replay's format, e.g. geojcbb_eval convert-victoria-park's), "
                 "with the noise its lines give");
  app.add_option("--seconds", c.seconds, "--log: only its first this many seconds (0: all)")->default_val(0);
  app.add_option("--strategies", c.names,
                 std::string("strategies, comma separated (") + kPresetsHelp +
                     "; default: the papers' six, PCJCBB and the robust preset PCJCBB+RL)")
      ->delimiter(',');
  app.add_option("--seed", c.seed, "simulation seed")->default_val(c.seed);
  app.add_option("--max-steps", c.o.max_steps, "control intervals to stream (0: the whole path)")->default_val(0);
  app.add_option("--timeout-ms", c.timeout_ms, "wait for each reply at most this long")->default_val(c.timeout_ms);
  add_run_options(app, c.o);
  app.add_flag("--check", c.check,
               "compare every ASSOC_RESULT and POSE, bit for bit, with the same node run in float in this process");
  app.add_flag("--budget", c.budget, "collect each scan's instruction counts (STATS after every scan)");
  app.add_option("--worst-case", c.worst,
                 "instead of a scenario: this many scans in which every observation is compatible with every "
                 "landmark, so JCBB runs into its node budget")
      ->default_val(0);
  app.add_option("--budget-csv", c.budget_csv, "write per-scan instruction counts here (implies --budget)");
}

// --check's verdict on a run: every ASSOC_RESULT and POSE equal, and one ASSOC_RESULT per scan and
// per SUBMAP_SEED sent. Sets rc to 1 when not.
std::string check_verdict(const RunResult& r, const MirrorReport& mr, int& rc) {
  // One ASSOC_RESULT per scan and one per SUBMAP_SEED sent.
  const std::uint64_t expected = static_cast<std::uint64_t>(r.scans) + mr.seeds_sent;
  std::string verdict = mr.mismatched == 0 ? "equal (" + std::to_string(mr.assoc_results) + " results, " +
                                                 std::to_string(mr.seeds_sent) + " of them seeds', " +
                                                 std::to_string(mr.poses) + " poses)"
                                           : std::to_string(mr.mismatched) + " DIFFER; first: " + mr.first_mismatch;
  if (mr.assoc_results != expected) {
    verdict += "; " + std::to_string(expected) + " results expected";
    rc = 1;
  }
  if (mr.mismatched != 0) rc = 1;
  return verdict;
}

// --budget: per strategy the instructions per scan (median and max), the parts that ran on some
// scans only, the largest step of each local map and the scans that hit the JCBB node budget.
void print_budgets(const std::vector<Method>& strategies, const std::vector<Budget>& budgets,
                   const std::string& source_name) {
  std::printf("instructions per scan (-icount shift=0; median / max over %s's scans)\n", source_name.c_str());
  std::printf("  %-8s %13s %13s %13s %13s %9s %13s %13s\n", "strategy", "assoc median", "assoc max", "step median",
              "step max", "scans>=20", "assoc20 med", "assoc20 max");
  for (std::size_t k = 0; k < strategies.size(); ++k) {
    const Budget& b = budgets[k];
    std::printf("  %-8s %13u %13u %13u %13u %9zu %13u %13u\n", strategies[k].name().c_str(), median(b.associate),
                maximum(b.associate), median(b.step), maximum(b.step), b.associate20.size(), median(b.associate20),
                maximum(b.associate20));
  }
  for (std::size_t k = 0; k < strategies.size(); ++k) {
    const Budget& b = budgets[k];
    auto line = [&](const std::vector<std::uint32_t>& v, const char* what) {
      std::vector<std::uint32_t> ran;
      for (const std::uint32_t c : v)
        if (c > 0) ran.push_back(c);
      if (ran.empty()) return;
      std::printf("  %-8s %zu scans %s: median %u, max %u instructions\n", strategies[k].name().c_str(), ran.size(),
                  what, median(ran), maximum(ran));
    };
    line(b.relocalise, "(lost or doubted) aligned against the map");
    line(b.loop, "had their loop closure checked");
    line(b.window, "ran clusters first or the hypothesis window");
    line(b.lost_test, "ran the lost test (tracking)");
    line(b.score, "scored candidate poses by their set likelihood (inside the rows above)");
    line(b.existence, "updated the landmarks' existence (log-odds; inside augment_review)");
  }
  for (std::size_t k = 0; k < strategies.size(); ++k) {
    const Budget& b = budgets[k];
    if (b.map_worst.size() < 2) continue;
    std::string worst_line;
    for (const std::uint32_t w : b.map_worst) worst_line += " " + std::to_string(w);
    std::printf("  %-8s the largest step of each local map [instructions]:%s\n", strategies[k].name().c_str(),
                worst_line.c_str());
  }
  for (std::size_t k = 0; k < strategies.size(); ++k) {
    const Budget& b = budgets[k];
    if (!b.budget_hit.empty()) {
      std::printf("  %-8s %zu scans hit the JCBB node budget; their association: max %u instructions\n",
                  strategies[k].name().c_str(), b.budget_hit.size(), maximum(b.budget_hit));
    }
  }
}

// --budget-csv: a run's per-scan instruction counts.
void write_budget_rows(std::ofstream& csv, const std::string& source_name, const std::string& strategy,
                       const Budget& b) {
  for (std::size_t i = 0; i < b.step.size(); ++i) {
    csv << '"' << source_name << "\"," << strategy << ',' << i << ',' << b.observations[i] << ',' << b.associate[i]
        << ',' << b.step[i] << ',' << b.predict_local[i] << ',' << b.update[i] << ',' << b.augment_review[i] << ','
        << b.lost_test[i] << ',' << b.score[i] << ',' << b.existence[i] << '\n';
  }
}

// What a session streams: the scenario simulated, or the log (its first seconds).
std::unique_ptr<RunSource> make_source(const QemuCli& c, const Scenario& sc, std::string& source_name) {
  source_name = sc.name;
  if (!c.log_path.empty()) {
    replay::LogSource all(replay::read_event_log(c.log_path), replay::LogNoise{});
    source_name =
        c.log_path + (c.seconds > 0 ? ", its first " + std::to_string(static_cast<int>(c.seconds)) + " s" : "");
    return std::make_unique<FirstSeconds>(all, c.seconds);
  }
  return std::make_unique<SimSource>(sc, c.seed, c.o.max_steps);
}

// The session: QEMU started, the firmware's capabilities printed, every strategy streamed (and
// checked, and its instructions counted, as asked), the firmware shut down. Returns the exit code.
int run_session(const QemuCli& c) {
  int rc = 0;
  const Scenario sc = load_scenario(c.scenario);
  std::string source_name;
  const std::unique_ptr<RunSource> source = make_source(c, sc, source_name);
  QemuMachine machine(c.q);
  // Open the pty before the CPU runs: QEMU drops UART output while nobody holds it.
  PosixSerial port(machine.pty());
  machine.cont();
  proto::Capabilities caps;
  {
    LinkClient hello(port, 2000);
    caps = hello.hello(10);  // waits on the handshake itself, no sleep
  }
  std::printf(
      "firmware %s on %s (%s)\n  boot id %08x, %d-byte scalars, up to %u observations, %u candidates, %u "
      "landmarks, %u JCBB nodes; schema %08x\n",
      c.q.elf.c_str(), machine.pty().c_str(), c.q.machine.c_str(), caps.boot_id, caps.scalar_bytes,
      caps.max_observations, caps.max_candidates, caps.max_landmarks, caps.max_jcbb_nodes, caps.schema_hash);
  const bool small = matches<SmallControllerBounds>(caps), dflt = matches<DefaultBounds>(caps),
             large = matches<LargeControllerBounds>(caps);
  if (c.check && !small && !dflt && !large)
    throw std::runtime_error("--check: the firmware's bounds are not a known configuration");
  std::vector<Method> strategies = select_methods(c.names, true);
  if (c.worst > 0 && c.check)
    throw std::runtime_error("--worst-case streams no scenario: it cannot be combined with --check");
  if (c.worst > 0) {
    worst_case(port, caps, strategies, c.worst, c.timeout_ms, c.o.step.node_budget);
    strategies.clear();
  }
  if (!strategies.empty())
    std::printf("%s%s, streamed through the emulated controller\n", source_name.c_str(),
                c.log_path.empty() ? (", seed " + std::to_string(c.seed)).c_str() : "");
  if (!strategies.empty()) print_score_header(c.check ? "bit-for-bit" : "");
  std::vector<Budget> budgets;
  std::ofstream csv;
  if (!c.budget_csv.empty()) {
    csv.open(c.budget_csv);
    csv << "scenario,strategy,scan,observations,instr_associate,instr_step,instr_predict_local,instr_update,"
           "instr_augment_review,instr_lost_test,instr_score,instr_existence\n";
  }
  for (const Method& m : strategies) {
    RunOptions ro = c.o;
    m.apply(ro);
    MirrorReport mr;
    Budget b;
    const auto t0 = std::chrono::steady_clock::now();
    RunSource& src = *source;
    const bool check = c.check, budget = c.budget;
    const int timeout_ms = c.timeout_ms;
    const RunResult r = small  ? run_one<SmallControllerBounds>(port, src, ro, check, budget, timeout_ms, mr, b)
                        : dflt ? run_one<DefaultBounds>(port, src, ro, check, budget, timeout_ms, mr, b)
                               : run_one<LargeControllerBounds>(port, src, ro, check, budget, timeout_ms, mr, b);
    const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const std::string verdict = c.check ? check_verdict(r, mr, rc) : std::string();
    print_score_row(m.name(), r, r.scans / secs, verdict);
    if (r.submaps.maps > 0) {
      std::printf(
          "  %-8s %d local maps handed over and joined: %d landmarks in the global map, %d fused, %d joins "
          "refused, %d wrong joins (labelled data), %d frames\n",
          m.name().c_str(), r.submaps.maps, r.landmarks, r.submaps.fused, r.submaps.refused, r.submaps.wrong,
          r.submaps.frames);
    }
    if (csv.is_open()) write_budget_rows(csv, source_name, m.name(), b);
    budgets.push_back(std::move(b));
  }
  if (c.budget && !strategies.empty()) print_budgets(strategies, budgets, source_name);
  LinkClient link(port, c.timeout_ms);
  std::printf("firmware STATS: %s\n", describe_stats(link.stats()).c_str());
  link.shutdown(0);
  const int status = machine.wait_exit(20000);
  std::printf("QEMU exited with status %d (the firmware's semihosting exit)\n", status);
  if (status != 0) rc = 1;
  return rc;
}

int run(int argc, char** argv) {
  CLI::App app{"geojcbb_qemu: stream a simulated scenario through the Cortex-M4F firmware on QEMU's mps2-an386"};
  QemuCli c;
  c.q.elf = GEOJCBB_FIRMWARE_ELF;
  add_options(app, c);
  CLI11_PARSE(app, argc, argv);
  c.budget = c.budget || !c.budget_csv.empty();
  try {
    return run_session(c);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "geojcbb_qemu: %s\n", e.what());
    return 1;
  }
}

}  // namespace

int main(int argc, char** argv) { return geojcbb::host::guarded_main(run, argc, argv); }
