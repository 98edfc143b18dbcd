// Closed-loop proofs on the core-level simulation (same classes as the nodes): passivity and
// boundedness with tanks under delay / jitter / loss, growth without them, tracking in free motion.
#include <cmath>
#include <cstdio>
#include <string>

#include <gtest/gtest.h>

#include "saras_teleop/teleop_sim.h"

using saras_teleop::runSimulation;
using saras_teleop::SimParams;
using saras_teleop::SimResult;

namespace
{
struct Scenario
{
  std::string name;
  double delay_ms;
  double jitter_ms;
  double loss;
  double burst;
  double hand_hz;
  double duration;
};

SimParams contactScenario(const Scenario& s, bool bypass)
{
  SimParams p;
  p.duration = s.duration;
  p.wall = 0.005;  // 5 mm in front of the slave: the operator pushes into it every cycle
  p.hand_frequency = s.hand_hz;
  for (auto* c : { &p.forward, &p.backward })
  {
    c->delay = s.delay_ms * 1e-3;
    c->jitter = s.jitter_ms * 1e-3;
    c->loss = s.loss;
    c->burst_length = s.burst;
  }
  p.backward.seed = 99;
  p.master_tank.bypass = p.slave_tank.bypass = bypass;
  p.slave_tank.damping_std.setConstant(0.002);  // [m/(N s)]
  p.slave_tank.damping_max.setConstant(0.01);
  p.trace_every = 100;
  return p;
}

void report(const Scenario& s, const char* mode, const SimResult& r)
{
  std::printf("[ sim ] %-14s %-7s E0=%6.2f J  E_out max=%8.3f J final=%8.3f J  master exc=%.3f m  slave exc=%.3f m  "
              "Tmin m/s=%.2f/%.2f J\n",
              s.name.c_str(), mode, r.E0, r.E_out_max, r.E_out_final, r.master_excursion, r.slave_excursion,
              r.T_master_min, r.T_slave_min);
}

class ClosedLoop : public ::testing::TestWithParam<Scenario>
{
};
}  // namespace

TEST_P(ClosedLoop, TanksKeepPassivityBypassDoesNot)
{
  const Scenario s = GetParam();
  const SimParams with = contactScenario(s, false);
  const SimResult r = runSimulation(with);
  report(s, "tanks", r);
  // passivity: the energy the teleoperator delivered at its ports never exceeded the energy it held
  EXPECT_LE(r.E_out_max, r.E0);
  EXPECT_GE(r.T_master_min, with.master_tank.T_min);
  EXPECT_GE(r.T_slave_min, with.slave_tank.T_min);
  // bounded: the hand alone moves the master 3 cm; the slave stays near the wall
  EXPECT_LT(r.master_excursion, 0.15);
  EXPECT_LT(r.slave_excursion, 0.06);

  const SimResult b = runSimulation(contactScenario(s, true));
  report(s, "bypass", b);
  if (s.delay_ms > 0.0 || s.jitter_ms > 0.0)
  {
    // without tanks the delayed loop is active: it keeps generating energy, an order of magnitude
    // more than the tanks ever let out (whose bound is E0)
    EXPECT_GT(b.E_out_final, 10.0 * std::max(r.E_out_max, 0.5)) << "no growth without tanks";
    // and the growth continues: second half of the run delivers energy as well
    const double half = b.trace[b.trace.size() / 2].E_out;
    EXPECT_GT(b.E_out_final - half, 0.25 * b.E_out_final);
  }
}

INSTANTIATE_TEST_CASE_P(
    Channels, ClosedLoop,
    // the 1 s case uses a slower hand so that the 2 s round trip is about a quarter period
    ::testing::Values(Scenario{ "delay0", 0, 0, 0, 1, 0.5, 30 }, Scenario{ "delay50", 50, 0, 0, 1, 0.5, 30 },
                      Scenario{ "delay200", 200, 0, 0, 1, 0.5, 30 },
                      Scenario{ "delay1000", 1000, 0, 0, 1, 0.125, 60 },
                      Scenario{ "jitter50+-50", 50, 100, 0, 1, 0.5, 30 },
                      Scenario{ "loss10", 50, 0, 0.1, 1, 0.5, 30 }, Scenario{ "burst10", 50, 0, 0.1, 20, 0.5, 30 }),
    [](const ::testing::TestParamInfo<Scenario>& i) {
      std::string n = i.param.name;
      for (auto& c : n)
        if (!std::isalnum(static_cast<unsigned char>(c)))
          c = '_';
      return n;
    });

// Free motion without delay: the slave set-point follows the scaled master, RMS error < 1 mm.
TEST(ClosedLoopTracking, FreeMotionRmsBelow1mm)
{
  SimParams p;
  p.duration = 20.0;
  p.wall = 1.0;  // out of reach
  const SimResult r = runSimulation(p);
  std::printf("[ sim ] free motion: tracking RMS = %.3f mm, slave excursion %.1f mm\n", r.tracking_rms * 1e3,
              r.slave_excursion * 1e3);
  EXPECT_LT(r.tracking_rms, 1e-3);
  EXPECT_GT(r.slave_excursion, 0.01);  // it actually moved (scaled 3 cm stroke = 1.5 cm)
}
