// Closed-loop core simulation of one channel, printed as CSV (for the demo report's energy plot).
// Usage: teleop_sim [delay_ms] [loss] [bypass 0|1] [duration_s] [burst_length] [jitter_ms]
#include <cstdio>
#include <cstdlib>

#include "saras_teleop/teleop_sim.h"

int main(int argc, char** argv)
{
  saras_teleop::SimParams p;
  const double delay = argc > 1 ? std::atof(argv[1]) * 1e-3 : 0.0;
  const double loss = argc > 2 ? std::atof(argv[2]) : 0.0;
  const bool bypass = argc > 3 && std::atoi(argv[3]) != 0;
  p.duration = argc > 4 ? std::atof(argv[4]) : 30.0;
  const double burst = argc > 5 ? std::atof(argv[5]) : 1.0;
  const double jitter = argc > 6 ? std::atof(argv[6]) * 1e-3 : 0.0;
  p.wall = 0.005;
  for (auto* c : { &p.forward, &p.backward })
  {
    c->delay = delay;
    c->loss = loss;
    c->burst_length = burst;
    c->jitter = jitter;
  }
  p.backward.seed = 2;
  p.master_tank.bypass = p.slave_tank.bypass = bypass;
  p.slave_tank.damping_std.setConstant(0.002);
  p.slave_tank.damping_max.setConstant(0.01);
  const saras_teleop::SimResult r = saras_teleop::runSimulation(p);
  std::printf("# E0=%.4f E_out_max=%.4f E_out_final=%.4f master_exc=%.4f slave_exc=%.4f Tm_min=%.3f Ts_min=%.3f "
              "tracking_rms=%.6f max_force=%.3f\n",
              r.E0, r.E_out_max, r.E_out_final, r.master_excursion, r.slave_excursion, r.T_master_min,
              r.T_slave_min, r.tracking_rms, r.max_force);
  std::printf("t,master_x,slave_x,setpoint_x,T_master,T_slave,E_out,force_dev\n");
  for (const auto& s : r.trace)
    std::printf("%.4f,%.6f,%.6f,%.6f,%.5f,%.5f,%.5f,%.4f\n", s.t, s.master_x, s.slave_x, s.setpoint_x, s.T_master,
                s.T_slave, s.E_out, s.force_dev);
  return 0;
}
