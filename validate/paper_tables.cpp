#include "validate/paper_tables.h"

#include "common/structure/accel.h"
#include "scenes/load_scene.h"
#include "validate/paper_figures.h"
#include "validate/table.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>

namespace ls {

namespace {

StructureSpec config_spec(const paper::Config& c) {
  StructureSpec s;
  s.kind = c.kind;
  s.depth = c.depth;
  s.subdivision = c.subdivision;
  return s;
}

std::string paper_name(const paper::Config& c) {
  return std::string(c.kind == StructureKind::FlatLs ? "F-LS" : "2L-LS") + " (" + std::to_string(c.depth) +
         "), N = " + std::to_string(c.subdivision);
}

// The paper scene a scene of ours is set beside: the instanced BUNNY SCENE for instanced scenes,
// else the architectural scene nearest in triangle count (on a log scale).
int nearest_paper_scene(size_t triangles, size_t objects, size_t instances) {
  if (instances >= 2 * objects) return 4;
  int best = 0;
  for (int i = 1; i < 4; ++i)
    if (std::abs(std::log(double(triangles) / paper::kSceneTriangles[size_t(i)])) <
        std::abs(std::log(double(triangles) / paper::kSceneTriangles[size_t(best)])))
      best = i;
  return best;
}

// Mean of the values that exist (NaN marks a missing one), with how many there were.
struct Mean {
  double sum = 0.0;
  int n = 0;
  void add(double v) {
    if (!std::isnan(v)) sum += v, ++n;
  }
  double value() const { return n ? sum / n : NAN; }
};

const RmseRow* row_of(const PaperScene& s, const std::string& structure, int start) {
  const RmseRow* r = s.study.find(structure, start);
  return r && r->refused.empty() ? r : nullptr;
}

double speedup(const RmseRow* r) {
  return r && r->speedup > 0.0 ? r->speedup : NAN;
}

// An error with its standard error: rmse_bias where estimated, else the RMSE (1 spp) taken as exact.
struct Err {
  double value = NAN, se = 0.0;
};

Err error_of(double rmse, const BiasEstimate& b) { return b.valid() ? Err{b.rmse_bias, b.rmse_bias_stderr} : Err{rmse, 0.0}; }

// Mean over scenes of the errors that exist, with the standard error of the mean (scenes independent).
struct MeanErr {
  double sum = 0.0, var = 0.0;
  int n = 0;
  void add(Err e) {
    if (!std::isnan(e.value)) sum += e.value, var += e.se * e.se, ++n;
  }
  Err value() const { return n ? Err{sum / n, std::sqrt(var) / n} : Err{}; }
};

// -1: a below b by more than two standard errors of the difference; 1: above; 0: within them.
int order(Err a, Err b) {
  const double margin = 2.0 * std::sqrt(a.se * a.se + b.se * b.se);
  if (a.value < b.value - margin) return -1;
  if (a.value > b.value + margin) return 1;
  return 0;
}

std::string err_text(Err e) {
  if (!(e.se > 0.0)) return rmse_text(e.value);
  BiasEstimate b;
  b.rmse_bias = e.value;
  b.rmse_bias_stderr = e.se;
  return bias_text(b);
}

// held: the data shows the claim; undecided: within the noise; the rest contradicts it.
std::string verdict(int held, int undecided, int total) {
  if (total == 0) return "not measured";
  if (held == total) return "holds";
  if (undecided == total) return "undecided";
  if (held + undecided == total) return "holds where decided";
  if (held == 0 && undecided == 0) return "does not hold";
  return "mixed";
}

}  // namespace

// The tables, ours beside the paper's, and the claims, from the scenes measured so far; writes
// paper.md and paper.json.
static void compose(const PaperOptions& options, const std::vector<const paper::Config*>& configs, const std::string& out_dir,
             PaperReport& report) {

  // ---- the tables, ours beside the paper's ----
  std::string md;
  const std::string device = report.scenes.front().study.device;
  md += "Ours: " + device + ", " + std::to_string(options.settings.width) + "x" + std::to_string(options.settings.height) +
        ", " + (options.settings.auto_spp.enabled ? "--spp auto from " : "") + std::to_string(options.settings.spp) +
        " spp, " + std::to_string(options.settings.bounces) +
        " bounces. Paper: i7-6800k + GTX 1080 (GLSL), 1024x1024.\n\n";
  if (options.tables.count(2)) {
    for (const PaperScene& s : report.scenes) {
      const int p = s.paper_scene;
      md += "### Table 2 analogue: " + s.scene + " (" + std::to_string(s.triangles) + " triangles, " +
            std::to_string(s.objects) + " objects, " + std::to_string(s.instances) + " instances) beside the paper's " +
            paper::kScenes[size_t(p)] + "\n\n";
      Table t;
      t.header = {"structure", "#LS", "MB", "s", "MB per LS", "paper #LS", "paper MB", "paper s", "paper MB per LS"};
      for (const paper::Config* c : configs) {
        const paper::Build& b = c->table2[size_t(p)];
        const RmseRow* r = nullptr;
        for (const RmseRow& row : s.study.rows)
          if (row.structure == config_spec(*c).name()) r = &row;
        std::vector<std::string> line = {paper_name(*c)};
        if (r && r->refused.empty()) {
          line.push_back(std::to_string(r->ls_nodes));
          line.push_back(fixed(double(r->bytes) / 1e6, 1));
          line.push_back(fixed(r->build_seconds, 2));
          line.push_back(r->ls_nodes ? fixed(double(r->bytes_ls) / 1e6 / double(r->ls_nodes), 3) : "-");
        } else {
          line.insert(line.end(), {"refused", "-", "-", "-"});
        }
        line.push_back(fixed(b.ls, 0));
        line.push_back(fixed(b.mb, 1));
        line.push_back(fixed(b.seconds, 2));
        line.push_back(fixed(b.mb / b.ls, 3));
        t.rows.push_back(line);
      }
      md += t.markdown() + "\n";
    }
  }

  // Averages over the scenes, as the paper averages over its five.
  std::map<std::string, Mean> speed, rmse1, rmse2, rmse3;
  std::map<std::string, MeanErr> bias1, bias2, bias3;
  if (options.tables.count(3)) {
    md += "### Table 3 analogue: averaged over " + std::to_string(report.scenes.size()) +
          " scene(s); speed-up of bounces >= 1 over F-BVH, RMSE (all samples, noise included) and rmse_bias ± its "
          "standard error (the error of the expected images) with the structure from bounce 1, 2, 3\n\n";
    Table t;
    t.header = {"structure", "speed-up", "paper speed-up", "RMSE 1", "RMSE 2", "RMSE 3", "rmse_bias 1", "rmse_bias 2",
                "rmse_bias 3", "paper RMSE 1", "paper RMSE 2", "paper RMSE 3"};
    t.rows.push_back({"F-BVH", "1.00", "1.00", "-", "-", "-", "-", "-", "-", "-", "-", "-"});
    Mean bvh2;
    for (const PaperScene& s : report.scenes) bvh2.add(speedup(row_of(s, "2l-bvh", 1)));
    t.rows.push_back({"2L-BVH", fixed(bvh2.value(), 2), fixed(paper::kTwoLevelBvhMraysPerS / paper::kFlatBvhMraysPerS, 2),
                      "-", "-", "-", "-", "-", "-", "-", "-", "-"});
    speed["2l-bvh"] = bvh2;
    for (const paper::Config* c : configs) {
      const std::string name = config_spec(*c).name();
      for (const PaperScene& s : report.scenes) {
        speed[name].add(speedup(row_of(s, name, 1)));
        const RmseRow* r1 = row_of(s, name, 1);
        const RmseRow* r2 = row_of(s, name, 2);
        const RmseRow* r3 = row_of(s, name, 3);
        rmse1[name].add(r1 ? r1->rmse : NAN);
        rmse2[name].add(r2 ? r2->rmse : NAN);
        rmse3[name].add(r3 ? r3->rmse : NAN);
        bias1[name].add(r1 ? error_of(r1->rmse, r1->bias) : Err{});
        bias2[name].add(r2 ? error_of(r2->rmse, r2->bias) : Err{});
        bias3[name].add(r3 ? error_of(r3->rmse, r3->bias) : Err{});
      }
      t.rows.push_back({paper_name(*c), fixed(speed[name].value(), 2), fixed(c->mrays_per_s / paper::kFlatBvhMraysPerS, 2),
                        rmse_text(rmse1[name].value()), rmse_text(rmse2[name].value()), rmse_text(rmse3[name].value()),
                        err_text(bias1[name].value()), err_text(bias2[name].value()), err_text(bias3[name].value()),
                        rmse_text(c->rmse[0]), rmse_text(c->rmse[1]), rmse_text(c->rmse[2])});
    }
    md += t.markdown() + "\n";
  }

  std::vector<Mean> t4_speed(paper::kSchedules.size()), t4_rmse(paper::kSchedules.size()), t4_mb(paper::kSchedules.size());
  std::vector<MeanErr> t4_bias(paper::kSchedules.size());
  if (options.tables.count(4)) {
    md += "### Table 4 analogue: structure per bounce 1, 2, 3, averaged over " + std::to_string(report.scenes.size()) +
          " scene(s); speed-up of bounces >= 1 over the all-F-BVH schedule\n\n";
    Table t;
    t.header = {"bounce 1, 2, 3", "our schedule", "MB", "speed-up", "RMSE", "rmse_bias", "paper MB", "paper speed-up",
                "paper RMSE"};
    for (size_t i = 0; i < paper::kSchedules.size(); ++i) {
      for (const PaperScene& s : report.scenes) {
        const ScheduleMeasure& m = s.table4[i];
        const ScheduleMeasure& base = s.table4[0];
        if (!m.refused.empty() || !base.refused.empty()) continue;
        t4_speed[i].add(m.speedup);
        t4_rmse[i].add(m.rmse);
        t4_bias[i].add(error_of(m.rmse, m.bias));
        t4_mb[i].add(double(m.bytes) / 1e6);
      }
      const paper::ScheduleRow& p = paper::kSchedules[i];
      t.rows.push_back({p.paper_name, p.schedule, fixed(t4_mb[i].value(), 1), fixed(t4_speed[i].value(), 2),
                        i == 0 ? "-" : rmse_text(t4_rmse[i].value()), i == 0 ? "-" : err_text(t4_bias[i].value()),
                        fixed(p.mb, 1),
                        fixed(p.mrays_per_s / paper::kSchedules[0].mrays_per_s, 2), p.rmse < 0 ? "-" : rmse_text(p.rmse)});
    }
    md += t.markdown() + "\n";
  }

  // ---- the paper's claims, checked on our data ----
  md += "### Which of the paper's claims hold here\n\n";
  nlohmann::json claims = nlohmann::json::array();
  auto claim = [&](const std::string& text, int held, int total, const std::string& evidence, int undecided = 0) {
    const std::string v = verdict(held, undecided, total);
    md += "- **" + v + "** (" + std::to_string(held) + " of " + std::to_string(total) +
          (undecided ? ", " + std::to_string(undecided) + " within two standard errors" : "") + "): " + text + ". " +
          evidence + "\n";
    claims.push_back({{"claim", text}, {"verdict", v}, {"held", held}, {"checked", total}, {"undecided", undecided},
                      {"evidence", evidence}});
  };
  if (options.tables.count(3)) {
    int held = 0, total = 0;
    std::string ev;
    for (const paper::Config* c : configs) {
      if (c->kind != StructureKind::FlatLs) continue;
      const double v = speed[config_spec(*c).name()].value();
      if (std::isnan(v)) continue;
      ++total;
      held += v > 1.0;
      ev += config_spec(*c).name() + " " + fixed(v, 2) + "x; ";
    }
    claim("F-LS traces bounces >= 1 faster than the exact F-BVH", held, total, ev);

    held = total = 0;
    ev.clear();
    const double b2 = speed["2l-bvh"].value();
    if (!std::isnan(b2)) {
      ++total;
      held += b2 < 1.0;
      ev += "2L-BVH " + fixed(b2, 2) + "x F-BVH; ";
    }
    for (int n : options.subdivisions) {
      Mean f, l;
      for (const paper::Config* c : configs)
        if (c->subdivision == n) (c->kind == StructureKind::FlatLs ? f : l).add(speed[config_spec(*c).name()].value());
      if (f.n && l.n) {
        ++total;
        held += l.value() < f.value();
        ev += "N=" + std::to_string(n) + ": 2L-LS " + fixed(l.value(), 2) + "x vs F-LS " + fixed(f.value(), 2) + "x; ";
      }
    }
    claim("two-level structures trace slower than their flat counterparts", held, total, ev);

    // Similar memory: each 2L-LS beside the F-LS whose memory is nearest on the same scene.
    int undecided = 0;
    held = total = 0;
    ev.clear();
    for (const PaperScene& s : report.scenes)
      for (const paper::Config* c : configs) {
        if (c->kind != StructureKind::TwoLevelLs) continue;
        const RmseRow* l = row_of(s, config_spec(*c).name(), 1);
        if (!l) continue;
        const RmseRow* best = nullptr;
        for (const paper::Config* f : configs) {
          const RmseRow* r = f->kind == StructureKind::FlatLs ? row_of(s, config_spec(*f).name(), 1) : nullptr;
          if (r && (!best || std::abs(std::log(double(r->bytes) / double(l->bytes))) <
                                 std::abs(std::log(double(best->bytes) / double(l->bytes)))))
            best = r;
        }
        if (!best) continue;
        ++total;
        const int o = order(error_of(l->rmse, l->bias), error_of(best->rmse, best->bias));
        held += o < 0;
        undecided += o == 0;
        ev += l->structure + " " + err_text(error_of(l->rmse, l->bias)) + " (" + fixed(double(l->bytes) / 1e6, 1) +
              " MB) vs " + best->structure + " " + err_text(error_of(best->rmse, best->bias)) + " (" +
              fixed(double(best->bytes) / 1e6, 1) + " MB); ";
      }
    claim("2L-LS is more accurate (rmse_bias) than F-LS of similar memory", held, total, ev, undecided);

    held = total = undecided = 0;
    ev.clear();
    for (const paper::Config* c : configs) {
      const std::string name = config_spec(*c).name();
      const Err a = bias1[name].value(), b = bias2[name].value(), d = bias3[name].value();
      if (std::isnan(a.value) || std::isnan(b.value) || std::isnan(d.value)) continue;
      ++total;
      const int ab = order(a, b), bd = order(b, d);
      held += ab > 0 && bd > 0;
      undecided += ab >= 0 && bd >= 0 && !(ab > 0 && bd > 0);
      if (!(ab > 0 && bd > 0)) ev += name + " " + err_text(a) + "/" + err_text(b) + "/" + err_text(d) + "; ";
    }
    claim("starting the Line Space at a later bounce lowers the error (rmse_bias, Table 3's columns)", held, total,
          ev.empty() ? "every structure: rmse_bias from bounce 1 > from 2 > from 3" : "exceptions: " + ev, undecided);

    held = total = undecided = 0;
    ev.clear();
    for (const paper::Config* a : configs)
      for (const paper::Config* b : configs) {
        const bool deeper = a->kind == b->kind && a->subdivision == b->subdivision && a->depth < b->depth;
        const bool finer = a->kind == b->kind && a->depth == b->depth && a->subdivision < b->subdivision;
        if (!deeper && !finer) continue;
        const Err ea = bias1[config_spec(*a).name()].value(), eb = bias1[config_spec(*b).name()].value();
        if (std::isnan(ea.value) || std::isnan(eb.value)) continue;
        ++total;
        const int o = order(eb, ea);
        held += o < 0;
        undecided += o == 0;
        if (o >= 0)
          ev += config_spec(*b).name() + " " + err_text(eb) + (o == 0 ? " within noise of " : " not below ") +
                config_spec(*a).name() + " " + err_text(ea) + "; ";
      }
    claim("a deeper integration depth or a finer subdivision lowers the error (rmse_bias)", held, total,
          ev.empty() ? "every pair" : "exceptions: " + ev, undecided);
  }
  if (options.tables.count(2)) {
    int held = 0, total = 0;
    std::string ev;
    for (const PaperScene& s : report.scenes) {
      if (s.instances < 2 * s.objects) continue;
      const RmseRow *f = nullptr, *l = nullptr;
      for (const RmseRow& r : s.study.rows) {
        if (r.structure == "f-ls:8:6" && r.refused.empty()) f = &r;
        if (r.structure == "2l-ls:4:6" && r.refused.empty()) l = &r;
      }
      if (!f || !l) continue;
      ++total;
      held += l->bytes_ls * 4 < f->bytes_ls;
      ev += s.scene + ": 2l-ls:4:6 " + fixed(double(l->bytes_ls) / 1e6, 1) + " MB of LS vs f-ls:8:6 " +
            fixed(double(f->bytes_ls) / 1e6, 1) + " MB; ";
    }
    claim("with instancing, 2L-LS needs far (here: over 4x) less Line Space memory than F-LS", held, total, ev);
  }
  if (options.tables.count(4)) {
    int held = 0, total = 0, undecided = 0;
    std::string ev;
    // Rows 1 -> 2 start the same 2L-LS one bounce later; rows 6 -> 1 trade error for speed.
    const Err r_late = t4_bias[1].value(), r_early = t4_bias[2].value();
    if (!std::isnan(r_late.value) && !std::isnan(r_early.value)) {
      ++total;
      const int o = order(r_late, r_early);
      held += o < 0;
      undecided += o == 0;
      ev += "2l-ls:4:6 from bounce 3 " + err_text(r_late) + " vs from bounce 2 " + err_text(r_early) + " (rmse_bias); ";
    }
    const double s_fls = t4_speed[6].value(), s_late = t4_speed[1].value();
    if (!std::isnan(s_fls) && !std::isnan(s_late)) {
      ++total;
      held += s_fls > s_late && s_late > 1.0;
      ev += "speed-up: F-LS from bounce 2 " + fixed(s_fls, 2) + "x, 2L-LS from bounce 3 " + fixed(s_late, 2) + "x; ";
    }
    claim("per-bounce schedules trade error for speed as Table 4 shows (later LS: less error; more LS: more speed)", held,
          total, ev, undecided);
  }

  report.markdown = md;
  nlohmann::json scenes = nlohmann::json::array();
  for (const PaperScene& s : report.scenes) {
    nlohmann::json t4 = nlohmann::json::array();
    for (const ScheduleMeasure& m : s.table4)
      t4.push_back({{"paper", m.paper_name}, {"schedule", m.schedule}, {"rmse", m.rmse},
                    {"rmse_bias", number_or_null(m.bias.rmse_bias)}, {"rmse_bias_stderr", number_or_null(m.bias.rmse_bias_stderr)},
                    {"noise_floor", number_or_null(m.bias.noise_floor)}, {"spp", m.spp}, {"spp_stop", m.spp_stop},
                    {"mrays_per_s", m.mrays_per_s}, {"exact_mrays_per_s", m.exact_mrays_per_s}, {"speedup_vs_bvh", m.speedup},
                    {"bytes", m.bytes},
                    {"refused", m.refused}});
    scenes.push_back({{"scene", s.scene}, {"triangles", s.triangles}, {"objects", s.objects}, {"instances", s.instances},
                      {"paper_scene", paper::kScenes[size_t(s.paper_scene)]}, {"study", s.study.json()}, {"table4", t4}});
  }
  report.json = {{"device", device}, {"scenes", scenes}, {"claims", claims}};
  std::filesystem::create_directories(out_dir);
  write_text_file(out_dir + "/paper.md", md);
  write_text_file(out_dir + "/paper.json", report.json.dump(2) + "\n");
}

PaperReport run_paper(const PaperOptions& options, const AccelOptions& accel_options, const std::string& out_dir,
                      const Log& log) {
  for (int t : options.tables)
    if (t < 2 || t > 4) throw InputError("--tables: the paper's tables are 2, 3 and 4 (not " + std::to_string(t) + ")");
  for (int n : options.subdivisions)
    if (n != 6 && n != 10) throw InputError("--subdivisions: the paper used N = 6 and N = 10 (not " + std::to_string(n) + ")");
  const bool renders = options.tables.count(3) || options.tables.count(4);
  if (renders && options.settings.bounces < 3)
    throw InputError("--bounces " + std::to_string(options.settings.bounces) + ": Tables 3 and 4 need 3 bounces");
  if (options.scenes.empty()) throw InputError("--scenes: give at least one scene");

  std::vector<const paper::Config*> configs;
  for (const paper::Config& c : paper::kConfigs)
    if (options.subdivisions.count(c.subdivision)) configs.push_back(&c);

  PaperReport report;
  for (const std::string& scene_spec : options.scenes) {
    log("== " + scene_spec);
    const Scene scene = load_scene(scene_spec);
    auto renderer = make_study_renderer(options.device, scene, accel_options);
    PaperScene ps;
    ps.scene = scene_spec;
    ps.triangles = triangle_count(scene);
    ps.objects = scene.meshes.size();
    ps.instances = scene.instances.size();
    ps.paper_scene = nearest_paper_scene(ps.triangles, ps.objects, ps.instances);

    std::vector<StructureSpec> specs;
    if (options.tables.count(3)) specs.push_back(parse_structure("2l-bvh"));
    for (const paper::Config* c : configs) specs.push_back(config_spec(*c));
    const ImageSettings& settings = options.settings;
    if (options.tables.count(3)) {
      const std::string dir = out_dir + "/" + file_safe(std::filesystem::path(scene_spec).filename().string());
      ps.study = run_rmse_study(*renderer, scene_spec, specs, settings, dir, options.heatmap_max, log, true);
      write_rmse_study(dir, ps.study);
    } else if (options.tables.count(2)) {
      ps.study.scene = scene_spec;
      ps.study.device = renderer->device();
      ps.study.settings = settings;
      for (const StructureSpec& spec : specs) {
        RmseRow row;
        row.structure = spec.name();
        try {
          static_cast<BuiltFigures&>(row) = built_figures(renderer->structure(spec));
        } catch (const InputError& e) {
          row.refused = e.what();
        }
        log(spec.name() + (row.refused.empty() ? ": built in " + fixed(row.build_seconds, 2) + " s" : ": refused"));
        ps.study.rows.push_back(row);
        renderer->release(spec);
      }
    }
    if (options.tables.count(4)) {
      Reference reference = render_reference(*renderer, settings);
      for (const paper::ScheduleRow& s : paper::kSchedules) {
        ScheduleMeasure sm;
        sm.paper_name = s.paper_name;
        sm.schedule = s.schedule;
        try {
          const Measured m = measure(*renderer, parse_schedule(s.schedule), settings, reference);
          static_cast<MeasuredFigures&>(sm) = m;
          sm.bytes = m.bytes;
        } catch (const InputError& e) {
          sm.refused = e.what();
        }
        log("Table 4 " + sm.schedule + ": " +
            (sm.refused.empty() ? "RMSE " + rmse_text(sm.rmse) + ", rmse_bias " + bias_text(sm.bias) + " (" +
                                      std::to_string(sm.spp) + " spp" + (sm.spp_stop.empty() ? "" : ", " + sm.spp_stop) +
                                      "), " + fixed(sm.mrays_per_s, 2) + " MRays/s"
                                : "refused: " + sm.refused));
        ps.table4.push_back(sm);
      }
    }
    report.scenes.push_back(std::move(ps));
    compose(options, configs, out_dir, report);  // written after every scene: long runs leave results early
  }
  return report;
}

}  // namespace ls
