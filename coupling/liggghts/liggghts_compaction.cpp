#include "coupling/liggghts/liggghts_compaction.h"

#include <sstream>
#include <stdexcept>

#include "btr/model/number_text.h"
#include "coupling/liggghts/liggghts_script.h"

namespace btr {

double liggghts_compaction_drag_rate(const Grains& grains, const Scene& scene, double damping) {
  double sum = 0.0;
  long n = 0;
  for (const SpeciesDamping& d : liggghts_species_damping(grains, scene, damping))
    if (d.grains > 0) sum += static_cast<double>(d.grains) * d.gamma / d.mean_mass, n += d.grains;
  if (n == 0) throw std::invalid_argument("compaction drag: no grain of the scene's species");
  return sum / static_cast<double>(n);
}

std::string liggghts_compaction_drag_fix(const Grains& grains, const Scene& scene, double damping) {
  const double c = liggghts_compaction_drag_rate(grains, scene, damping);
  const std::string rate = g17(c);
  std::string s = "# The compaction's drag, damping " + g6(damping) + ": F = -c m v, one rate c = " + g6(c) +
                  " 1/s for every grain (the mean of gamma / m over\n"
                  "# the species' mean grains, gamma as in fix viscous), so that grains of every size fall through the pores\n"
                  "# alike; a coefficient per species let the large ones sink past the small (coupling/README.md).\n";
  for (const char* k : {"x", "y", "z"})
    s += "variable btr_drag_" + std::string(k) + " atom -" + rate + "*mass*v" + k + "\n";
  return s + "fix " + kCompactionDampingFix + " all addforce v_btr_drag_x v_btr_drag_y v_btr_drag_z\n";
}

std::string liggghts_compaction_setup(const CompactionPlan& c, int dimension) {
  std::ostringstream s;
  // A slab compaction watches one slab's window at a time: its z bounds and measure are variables, set per slab.
  const bool slabs = !c.slabs.empty();
  const std::string zlo = slabs ? "v_btr_wlo" : g17(c.window_lo.z()), zhi = slabs ? "v_btr_whi" : g17(c.window_hi.z());
  if (slabs)
    s << "\n# The window's z bounds and measure: the slab's being compacted (set before each slab).\n"
      << "variable btr_wlo equal " << g17(c.slabs.front().window_lo_z) << "\n"
      << "variable btr_whi equal " << g17(c.slabs.front().window_hi_z) << "\n"
      << "variable btr_wmeasure equal " << g17(c.slabs.front().window_measure) << "\n";
  // LIGGGHTS 3.8's atom-style variables have no min/max: min(x, y) = (x + y - |x - y|) / 2, max likewise.
  auto max = [](const std::string& x, const std::string& y) { return "0.5*(" + x + "+" + y + "+abs(" + x + "-(" + y + ")))"; };
  auto min = [](const std::string& x, const std::string& y) { return "0.5*(" + x + "+" + y + "-abs(" + x + "-(" + y + ")))"; };
  s << "\n# Compaction to the target packing fraction: the solid fraction of the bulk window (btr measure's window of\n"
    << "# the starting packing, its top lowered by the compaction to come): each grain's part between the window's\n"
    << "# planes, exactly (cap volumes; 2D: disk segments) in z, times (walled containers) the fraction of the grain\n"
    << "# between the window's side planes in x (and y), exact where one side cuts it (near the window's edges, a\n"
    << "# grain cut by two planes is the product's approximation). Counting whole the grains centred inside instead\n"
    << "# misread a cylinder's window by 0.006 (docs/guide/relax.md).\n";
  // [a, b]: the grain's extent [u - r, u + r] along axis u clipped to [lo, hi], empty (a = b) where they do not meet
  auto cut = [&](const std::string& name, const std::string& u, const std::string& lo, const std::string& hi) {
    s << "variable btr_cut" << name << "_a0 atom " << max(lo, u + "-c_btr_radius") << "\n"
      << "variable btr_cut" << name << "_a atom " << min("v_btr_cut" + name + "_a0", u + "+c_btr_radius") << "\n"
      << "variable btr_cut" << name << "_b0 atom " << min(hi, u + "+c_btr_radius") << "\n"
      << "variable btr_cut" << name << "_b atom " << max("v_btr_cut" + name + "_b0", "v_btr_cut" + name + "_a") << "\n";
  };
  // the grain's part between the planes of axis u: volume (3D, pi r^2 (b - a) - pi ((b-u)^3 - (a-u)^3) / 3) or
  // area (2D, r^2 [v sqrt(1 - v^2) + asin v] between v = (a - u) / r and (b - u) / r, v kept in [-1, 1])
  auto part = [&](const std::string& name, const std::string& u) -> std::string {
    const std::string a = "v_btr_cut" + name + "_a", b = "v_btr_cut" + name + "_b";
    if (dimension == 3)
      return "3.1415926535897931*(c_btr_radius*c_btr_radius*(" + b + "-" + a + ")-((" + b + "-" + u + ")^3-(" + a +
             "-" + u + ")^3)/3.0)";
    const std::string va = "v_btr_cut" + name + "_va", vb = "v_btr_cut" + name + "_vb";
    s << "variable btr_cut" << name << "_va atom " << min(max("(" + a + "-" + u + ")/c_btr_radius", "-1.0"), "1.0") << "\n"
      << "variable btr_cut" << name << "_vb atom " << min(max("(" + b + "-" + u + ")/c_btr_radius", "-1.0"), "1.0") << "\n";
    return "c_btr_radius*c_btr_radius*(" + vb + "*sqrt(abs(1.0-" + vb + "^2))+asin(" + vb + ")-" + va +
           "*sqrt(abs(1.0-" + va + "^2))-asin(" + va + "))";
  };
  const std::string whole = dimension == 3 ? "(4.1887902047863905*c_btr_radius^3)" : "(3.1415926535897931*c_btr_radius^2)";
  cut("", "z", zlo, zhi);
  std::string volume = part("", "z");
  if (!c.slab) {
    cut("x", "x", g17(c.window_lo.x()), g17(c.window_hi.x()));
    s << "variable btr_frac_x atom (" << part("x", "x") << ")/" << whole << "\n";
    volume = "(" + volume + ")*v_btr_frac_x";
    if (dimension == 3) {
      cut("y", "y", g17(c.window_lo.y()), g17(c.window_hi.y()));
      s << "variable btr_frac_y atom (" << part("y", "y") << ")/" << whole << "\n";
      volume += "*v_btr_frac_y";
    }
  }
  s << "variable btr_grain_volume atom " << volume << (dimension == 3 ? "\n" : "   # 2D: areas\n")
    << "compute btr_bulk_volume all reduce sum v_btr_grain_volume\n"
    << "variable btr_phi equal c_btr_bulk_volume/" << (slabs ? "v_btr_wmeasure" : g17(c.window_measure)) << "\n";
  return s.str();
}

namespace {

// A check's steps, then the blow-up bound. No set-up: each one of LIGGGHTS 3.8 takes energy out of the frictionless
// collapse like extra damping, so a settled bed's coordination followed the check interval (docs/guide/settle.md,
// "The compaction's checks without set-ups"). A `run 0` sets up before each block (fixes, types, groups, step).
std::string check_run(const CompactionPlan& c) {
  return "run " + std::to_string(c.steps_per_check) + " pre no post no\n" +
         "if \"${btr_ekin} > ${btr_bound}\" then &\n"
         "  \"print 'BTR-FAILURE kinetic energy ${btr_ekin} J above the bound ${btr_bound} J at t = ${btr_time} s'\" quit\n";
}

// CompactionPlan::slabs, slab by slab: the slab's grains (btr_slab) take their species' twin type, the grains up
// to its last join btr_released (the integrator's group), and the check loop runs on its window until the target
// or rest; then the slab's grains take their species' type again. The grains above (btr_held) never move, so the
// pairs between two of them are left out of the pair list: their forces act on no integrated grain. Each slab
// prints "BTR-COMPACTION-SLAB k K reached|rest|max-time t = T s phi = P", and after the last
// "BTR-COMPACTION-END reached|not-reached ..." (reached: every slab did).
std::string slab_loop(const CompactionPlan& c, const Scene& scene, double arming_time) {
  std::ostringstream s;
  const std::string target = g17(c.target), rest = g17(c.rest_kinetic), scale = g6(c.friction_scales.front());
  const std::size_t n_species = scene.grains.components.size(), n = c.slabs.size();
  s << "# Compaction in " << n << " slabs from the floor up (the grains above the slab held, not integrated): the\n"
    << "# slab frictionless (friction x " << scale << ") until its window reaches " << g6(c.target) << ", checked every "
    << c.steps_per_check << " steps; then its friction back and the next slab.\n";
  for (std::size_t t = 0; t < n_species; ++t)
    s << "group btr_species_" << t + 1 << " type " << t + 1 << "\n";
  s << "variable btr_slabs_reached equal 0\n";
  for (std::size_t k = 0; k < n; ++k) {
    const CompactionPlan::Slab& slab = c.slabs[k];
    const std::string id = std::to_string(k + 1), first = std::to_string(k == 0 ? 1 : c.slabs[k - 1].last + 2),
                      last = std::to_string(slab.last + 1), of = " " + id + " " + std::to_string(n);
    s << "group btr_released id <> 1 " << last << "\n";
    if (k == 0) s << "fix btr_integrate btr_released nve/sphere\n";
    if (k > 0) s << "neigh_modify exclude none\n"
                 << "group btr_held delete\n";
    if (k + 1 < n) s << "group btr_held id > " << last << "\n"
                     << "neigh_modify exclude group btr_held btr_held\n";
    s << "group btr_slab id <> " << first << " " << last << "\n";
    for (std::size_t t = 0; t < n_species; ++t)
      s << "group btr_slab_" << t + 1 << " intersect btr_slab btr_species_" << t + 1 << "\n"
        << "set group btr_slab_" << t + 1 << " type " << liggghts_slab_twin_type(scene, t) << "\n";
    s << "variable btr_wlo equal " << g17(slab.window_lo_z) << "\n"
      << "variable btr_whi equal " << g17(slab.window_hi_z) << "\n"
      << "variable btr_wmeasure equal " << g17(slab.window_measure) << "\n"
      << "run 0 post no\n"  // the new types, group and integrator set up
      << "variable btr_crest equal ${btr_time}+" << g17(arming_time) << "\n"
      << "label btr_slab_" << id << "\n"
      << "variable btr_slab_check_" << id << " loop " << c.max_checks_per_scale << "\n"
      << check_run(c)
      << "if \"${btr_phi} >= " << target << "\" then &\n"
      << "  \"print 'BTR-COMPACTION-SLAB" << of << " reached t = ${btr_time} s phi = ${btr_phi}'\" &\n"
      << "  \"variable btr_slabs_reached equal ${btr_slabs_reached}+1\" &\n"
      << "  \"jump SELF btr_slab_done_" << id << "\"\n"
      << "if \"${btr_time} >= ${btr_crest} && ${btr_kmean} < " << rest << " && ${btr_ekin} < " << rest << "\" then &\n"
      << "  \"print 'BTR-COMPACTION-SLAB" << of << " rest t = ${btr_time} s phi = ${btr_phi}'\" &\n"
      << "  \"jump SELF btr_slab_done_" << id << "\"\n"
      << "next btr_slab_check_" << id << "\n"
      << "jump SELF btr_slab_" << id << "\n"
      << "print \"BTR-COMPACTION-SLAB" << of << " max-time t = ${btr_time} s phi = ${btr_phi}\"\n"
      << "label btr_slab_done_" << id << "\n";
    for (std::size_t t = 0; t < n_species; ++t)
      s << "set group btr_slab_" << t + 1 << " type " << t + 1 << "\n"
        << "group btr_slab_" << t + 1 << " delete\n";
    s << "group btr_slab delete\n";
  }
  s << "if \"${btr_slabs_reached} == " << n << "\" then &\n"
    << "  \"print 'BTR-COMPACTION-END reached friction x " << scale << " t = ${btr_time} s phi = ${btr_phi}'\" &\n"
    << "else &\n"
    << "  \"print 'BTR-COMPACTION-END not-reached friction x " << scale << " t = ${btr_time} s phi = ${btr_phi}'\"\n";
  return s.str();
}

}  // namespace

std::string liggghts_compaction_loop(const CompactionPlan& c, const Scene& scene,
                                     double settle_damping, double settle_timestep, double arming_time) {
  std::ostringstream s;
  const std::string target = g17(c.target), rest = g17(c.rest_kinetic);
  const bool slabs = !c.slabs.empty();
  s << "# Compaction: friction x";
  for (double f : c.friction_scales) s << " " << g6(f);
  s << " in turn (the next once the bed is at rest, kinetic energy and its mean below " << g6(c.rest_kinetic)
    << " J),\n# damping " << g6(c.damping) << ", until btr_phi >= " << g6(c.target) << ", checked every "
    << c.steps_per_check << " steps; each scale runs at most max_time;\n# time step " << g6(c.timestep)
    << " s (fraction " << g6(c.timestep_fraction) << " of the rule's characteristic time; the settle's: "
    << g6(settle_timestep) << " s).\n";
  if (c.timestep != settle_timestep) s << "timestep " << g17(c.timestep) << "\n";
  if (slabs) s << slab_loop(c, scene, arming_time);
  for (std::size_t k = 0; !slabs && k < c.friction_scales.size(); ++k) {
    const std::string scale = g6(c.friction_scales[k]), n = std::to_string(k + 1);
    if (k > 0) s << liggghts_friction_fixes(scene, c.friction_scales[k]);
    s << "run 0 post no\n";
    s << "variable btr_crest equal ${btr_time}+" << g17(arming_time) << "\n"
      << "label btr_compact_" << n << "\n"
      << "variable btr_compact_check_" << n << " loop " << c.max_checks_per_scale << "\n"
      << check_run(c)
      << "if \"${btr_phi} >= " << target << "\" then &\n"
      << "  \"print 'BTR-COMPACTION-END reached friction x " << scale << " t = ${btr_time} s phi = ${btr_phi}'\" &\n"
      << "  \"jump SELF btr_compaction_done\"\n"
      << "if \"${btr_time} >= ${btr_crest} && ${btr_kmean} < " << rest << " && ${btr_ekin} < " << rest
      << "\" then \"jump SELF btr_compact_rest_" << n << "\"\n"
      << "next btr_compact_check_" << n << "\n"
      << "jump SELF btr_compact_" << n << "\n"
      << "label btr_compact_rest_" << n << "\n"
      << "print \"BTR-COMPACTION-REST friction x " << scale << " t = ${btr_time} s phi = ${btr_phi}\"\n";
  }
  if (!slabs)
    s << "print \"BTR-COMPACTION-END not-reached friction x " << g6(c.friction_scales.back())
      << " t = ${btr_time} s phi = ${btr_phi}\"\n";
  s << "label btr_compaction_done\n"
    << "# The scene's friction back, every grain stopped, the settle's damping and step, the stop rule armed anew.\n"
    << (c.timestep != settle_timestep ? "timestep " + g17(settle_timestep) + "\n" : std::string())
    << liggghts_friction_fixes(scene, 1.0, slabs)
    << "velocity all set 0.0 0.0 0.0\n"
    << "set group all omegax 0.0 omegay 0.0 omegaz 0.0\n";
  if (c.damping > 0) s << "unfix " << kCompactionDampingFix << "\n";
  if (settle_damping > 0) s << liggghts_local_damping_fix("btr_damping", settle_damping);
  s << "run 0 post no\n"
    << "variable btr_tarm equal ${btr_time}+" << g17(arming_time) << "\n"
    << "variable btr_armed equal 0\n\n";
  return s.str();
}

}  // namespace btr
