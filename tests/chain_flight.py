"""docs/results.md, "The chain in free flight": the jointed robot in free flight: no contact, no gravity, joint torques below 1e-12 N m.
Energy, linear and angular momentum and the centre of mass's straight line over 2 s, at dt = 1, 0.5,
0.25, 0.125 ms (fast stepper), from one random state, read two ways:

* as given: qd0 is the first step's starting velocity, and the state at the end is (q_N, qd_N);
* staggered: the step reads qd as the velocity at the middle of the last step (q+ = q + dt qd+), so
  the run starts from qd0 - dt/2 a0 (a0 the acceleration at the start: its velocity at t = dt/2 is
  then qd0 + dt/2 a0) and the end's velocity is the mean of the last two (at t_N)."""
import sys
import numpy as np
from bodies import centre_of_mass, cobra_in_free_flight, hold_joints
from cobra_ref.dynamics import forward_dynamics, kinetic_energy, spatial_momentum
from cobra_ref.step import StepSettings
from cobra_ref.steppers import make_stepper

model, q0, qd0 = cobra_in_free_flight()
mass = sum(model.mass)
a0 = forward_dynamics(model, q0, qd0, np.zeros(model.nv))

T = float(sys.argv[1]) if len(sys.argv) > 1 else 2.0
E0, h0, c0 = kinetic_energy(model, q0, qd0), spatial_momentum(model, q0, qd0), centre_of_mass(model, q0)
v_c = h0[3:] / mass  # the centre of mass's velocity (linear momentum / mass)
for staggered in (False, True):
    for dt in (1e-3, 5e-4, 2.5e-4, 1.25e-4):
        st = make_stepper(sys.argv[2] if len(sys.argv) > 2 else "fast", model, StepSettings(dt=dt))
        q, qd = q0.copy(), qd0 - 0.5 * dt * a0 if staggered else qd0.copy()
        n = int(round(T / dt))
        for k in range(n):
            r = st.step(q, qd, k * dt, hold_joints)
            q, qd = r.q, r.qd
        v = 0.5 * (qd + st.step(q, qd, n * dt, hold_joints).qd) if staggered else qd
        E, h, c = kinetic_energy(model, q, v), spatial_momentum(model, q, v), centre_of_mass(model, q)
        print(f"{'staggered' if staggered else 'as given'} dt {dt*1e3:g} ms: energy {100*(E-E0)/E0:+.4f} %  "
              f"linear momentum {100*np.linalg.norm(h[3:]-h0[3:])/np.linalg.norm(h0[3:]):.4f} %  "
              f"angular momentum {100*np.linalg.norm(h[:3]-h0[:3])/np.linalg.norm(h0[:3]):.4f} %  "
              f"com off its line {1e3*np.linalg.norm(c - (c0 + v_c*n*dt)):.3f} mm  (E0 {E0:.3f} J)", flush=True)
