#!/usr/bin/env python3
"""Hoist-pendulum benchmark, Exudyn side (ANCF cable + payload), for comparison
with the bevy_rapier_cable rope solver.

Model (see README.md in this folder):
  * 20 m rope, 1.6 kg/m, EA = 2e7 N, EI = 50 N m^2, no damping, no torsion
    (Exudyn 3D ObjectANCFCable with NodePointSlope1 nodes).
  * top node pinned at the origin (position fixed, slope free) by a spherical joint
    to ground.
  * payload "sphere" (default): rigid body (NodeRigidBodyRxyz + ObjectRigidBody),
    m = 1000 kg, r = 0.3 m, inertia 0.4 m r^2, centre 0.3 m beyond the rope end
    along the rope; the rope end node is joined to the sphere's surface point by an
    ObjectJointSpherical.  payload "point": 1000 kg mass point (NodePoint + MassPoint)
    at the rope end, joined by an ObjectJointSpherical (zero offset).
  * gravity 9.81 m/s^2 along -y (LoadMassProportional on every element and payload).
  * released from rest, straight unstretched rope at 30 deg from vertical in x-y.
  * generalized-alpha (Exudyn SolveDynamic, implicit), fixed step h = 1/60 s,
    1200 steps = 20 s, no adaptive step, one thread, sparse linear solver.
"""
import argparse
import json
import math
import platform
import sys
import time

import numpy as np
if '--fast' in sys.argv:
    # must be set before the first import of exudyn: loads exudynCPPfast (no range checks,
    # AVX2) instead of the default exudynCPP module
    sys.exudynFast = True
import exudyn as exu
from exudyn.itemInterface import (
    ObjectGround, NodePointSlope1, ObjectANCFCable, MarkerBodyMass, LoadMassProportional,
    MarkerNodePosition, MarkerBodyPosition, ObjectJointSpherical, NodeRigidBodyRxyz,
    ObjectRigidBody, NodePoint, ObjectMassPoint, SensorBody,
)

# ---------------------------------------------------------------- benchmark data
L_ROPE = 20.0          # m
RHO_A = 1.6            # kg/m
EA = 2.0e7             # N
EI = 50.0              # N m^2
M_PAYLOAD = 1000.0     # kg
R_SPHERE = 0.3         # m
G = 9.81               # m/s^2
ANGLE = math.radians(30.0)
H = 1.0 / 60.0         # s
T_END = 20.0           # s
N_STEPS = 1200         # T_END / H

# reference values of the bevy_rapier_cable solver at h/4: (period s, mean stretch)
REFERENCE = {10: (9.1749, 5.287e-4), 100: (9.1748, 5.281e-4), 1000: (9.1748, 5.280e-4)}

# Gauss-Legendre points on [0,1] for the arc length of the cubic Hermite (ANCF) elements
_GX, _GW = np.polynomial.legendre.leggauss(5)
_GX = 0.5 * (_GX + 1.0)
_GW = 0.5 * _GW
# derivatives of the cubic Hermite shape functions w.r.t. xi at the Gauss points
_DS1 = 6 * _GX**2 - 6 * _GX
_DS2 = 3 * _GX**2 - 4 * _GX + 1
_DS3 = -6 * _GX**2 + 6 * _GX
_DS4 = 3 * _GX**2 - 2 * _GX


def build(n_el, payload, spectral_radius, linear_solver, record_rope):
    """Build the model; return (mbs, simulationSettings, info dict, recorder dict)."""
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    d = np.array([math.sin(ANGLE), -math.cos(ANGLE), 0.0])
    grav = [0.0, -G, 0.0]
    le = L_ROPE / n_el

    ground = mbs.AddObject(ObjectGround(referencePosition=[0, 0, 0]))

    nodes = []
    for i in range(n_el + 1):
        p = d * (i * le)
        nodes.append(mbs.AddNode(NodePointSlope1(referenceCoordinates=list(p) + list(d))))
    for i in range(n_el):
        oc = mbs.AddObject(ObjectANCFCable(nodeNumbers=[nodes[i], nodes[i + 1]], length=le,
                                           massPerLength=RHO_A, axialStiffness=EA,
                                           bendingStiffness=EI))
        mm = mbs.AddMarker(MarkerBodyMass(bodyNumber=oc))
        mbs.AddLoad(LoadMassProportional(markerNumber=mm, loadVector=grav))

    # pin at the top: spherical joint between ground point (origin) and node 0 position
    mg = mbs.AddMarker(MarkerBodyPosition(bodyNumber=ground, localPosition=[0, 0, 0]))
    m0 = mbs.AddMarker(MarkerNodePosition(nodeNumber=nodes[0]))
    mbs.AddObject(ObjectJointSpherical(markerNumbers=[mg, m0]))

    mEnd = mbs.AddMarker(MarkerNodePosition(nodeNumber=nodes[-1]))
    if payload == 'sphere':
        c = d * (L_ROPE + R_SPHERE)
        I = 0.4 * M_PAYLOAD * R_SPHERE**2
        nP = mbs.AddNode(NodeRigidBodyRxyz(referenceCoordinates=list(c) + [0, 0, 0]))
        oP = mbs.AddObject(ObjectRigidBody(nodeNumber=nP, mass=M_PAYLOAD,
                                           inertia=[I, I, I, 0, 0, 0]))
        # body frame == global frame in the reference configuration (Rxyz angles = 0)
        mS = mbs.AddMarker(MarkerBodyPosition(bodyNumber=oP, localPosition=list(-R_SPHERE * d)))
    else:
        nP = mbs.AddNode(NodePoint(referenceCoordinates=list(d * L_ROPE)))
        oP = mbs.AddObject(ObjectMassPoint(nodeNumber=nP, mass=M_PAYLOAD))
        mS = mbs.AddMarker(MarkerBodyPosition(bodyNumber=oP, localPosition=[0, 0, 0]))
    mbs.AddObject(ObjectJointSpherical(markerNumbers=[mEnd, mS]))
    mbs.AddLoad(LoadMassProportional(markerNumber=mbs.AddMarker(MarkerBodyMass(bodyNumber=oP)),
                                     loadVector=grav))

    # payload centre position, recorded in C++ at every step, kept in memory, no file
    sPay = mbs.AddSensor(SensorBody(bodyNumber=oP, localPosition=[0, 0, 0],
                                    outputVariableType=exu.OutputVariableType.Position,
                                    writeToFile=False, storeInternal=True))

    mbs.Assemble()

    # rope length at every step, from the ODE2 coordinates (post-step user function)
    rec = {'t': [], 'chord': [], 'arc': [], 'tip': []}
    idx = np.array([mbs.GetNodeODE2Index(nd) for nd in nodes])
    iPos = idx[:, None] + np.arange(3)[None, :]
    iSlope = idx[:, None] + 3 + np.arange(3)[None, :]
    qRef = mbs.systemData.GetODE2Coordinates(configuration=exu.ConfigurationType.Reference)
    pRef, sRef = qRef[iPos], qRef[iSlope]

    def rope_lengths(q):
        p = pRef + q[iPos]
        s = sRef + q[iSlope]
        chord = np.linalg.norm(p[1:] - p[:-1], axis=1).sum()
        # r'(x) = (1/le)[dS1 r0 + dS2 le r0' + dS3 r1 + dS4 le r1'];  arc = le * sum_g w_g |r'|
        dr = (np.multiply.outer(_DS1, p[:-1]) + np.multiply.outer(_DS2 * le, s[:-1])
              + np.multiply.outer(_DS3, p[1:]) + np.multiply.outer(_DS4 * le, s[1:])) / le
        arc = le * np.einsum('g,ge->', _GW, np.linalg.norm(dr, axis=2))
        tip = np.linalg.norm(p[-1] - p[0])
        return chord, arc, tip

    if record_rope:
        def post_step(mbs_, t):
            q = mbs_.systemData.GetODE2Coordinates(copy=False)
            c_, a_, t_ = rope_lengths(q)
            rec['t'].append(t)
            rec['chord'].append(c_)
            rec['arc'].append(a_)
            rec['tip'].append(t_)
            return True
        mbs.SetPostStepUserFunction(post_step)

    ss = exu.SimulationSettings()
    ti = ss.timeIntegration
    ti.solverType = exu.DynamicSolverType.GeneralizedAlpha
    ti.generalizedAlpha.spectralRadius = spectral_radius
    ti.endTime = T_END
    ti.numberOfSteps = N_STEPS
    ti.adaptiveStep = False
    ti.automaticStepSize = False
    ti.verboseMode = 0
    ss.parallel.numberOfThreads = 1
    ss.linearSolver.solverType = (exu.LinearSolverType.EigenSparse if linear_solver == 'sparse'
                                  else exu.LinearSolverType.EXUdense)
    ss.solution.file.write = False          # no solution file
    ss.solution.sensors.writePeriod = 0.0   # sensor sample at every step (memory only)
    ss.show.statistics = False
    ss.show.computationTime = False

    info = {'sensor': sPay, 'nCoordinates': mbs.systemData.ODE2Size(),
            'nAE': mbs.systemData.AEsize()}
    return mbs, ss, info, rec


def zero_crossing_period(t, x):
    t = np.asarray(t)
    x = np.asarray(x)
    tc = []
    for k in range(len(x) - 1):
        if x[k] == 0.0:
            tc.append(t[k])
        elif x[k] * x[k + 1] < 0.0:
            tc.append(t[k] - x[k] * (t[k + 1] - t[k]) / (x[k + 1] - x[k]))
    if len(tc) < 2:
        return float('nan'), len(tc)
    return 2.0 * (tc[-1] - tc[0]) / (len(tc) - 1), len(tc)


def run_once(n_el, args, record_rope=True):
    t0 = time.perf_counter()
    mbs, ss, info, rec = build(n_el, args.payload, args.spectral_radius, args.linear_solver,
                               record_rope)
    build_wall = time.perf_counter() - t0

    err = None
    c0, w0 = time.process_time(), time.perf_counter()
    try:
        ok = mbs.SolveDynamic(ss, storeSolver=True)
    except Exception as e:  # Exudyn raises on Newton failure in some versions
        ok, err = False, repr(e)
    cpu, wall = time.process_time() - c0, time.perf_counter() - w0

    solver = mbs.sys.get('dynamicSolver')
    it = solver.it if solver is not None else None
    t_reached = float(mbs.systemData.GetTime())
    nsteps = int(round(t_reached / H))   # steps actually taken (fixed step)
    newton = int(it.newtonStepsCount) if it is not None else None
    jac = int(it.newtonJacobiCount) if it is not None else None
    rejected = int(it.rejectedModifiedNewtonSteps) if it is not None else None

    data = mbs.GetSensorStoredData(info['sensor'])   # columns: t, x, y, z
    period, ncross = zero_crossing_period(data[:, 0], data[:, 1])
    res = {
        'N': n_el, 'payload': args.payload,
        'model': '3D ObjectANCFCable, payload ' + (
            'rigid sphere (Rxyz) + SphericalJoint, 0.3 m offset' if args.payload == 'sphere'
            else 'mass point + SphericalJoint at rope end (no 0.3 m offset)'),
        'cpu_s': cpu, 'wall_s': wall, 'build_wall_s': build_wall,
        'rtf': T_END / wall if wall > 0 else float('nan'),
        'completed': bool(ok) and abs(t_reached - T_END) < 1e-9,
        't_reached': t_reached, 'error': err,
        'steps': nsteps, 'newton_iterations': newton, 'jacobians': jac,
        'rejected_modified_newton_steps': rejected,
        'newton_per_step': (newton / nsteps) if (newton is not None and nsteps) else None,
        'jacobians_per_step': (jac / nsteps) if (jac is not None and nsteps) else None,
        'period_s': period, 'zero_crossings': ncross,
        'nODE2': info['nCoordinates'], 'nAE': info['nAE'],
        'spectral_radius': args.spectral_radius, 'linear_solver': args.linear_solver,
        'recorded_rope_length': record_rope,
    }
    if record_rope and rec['t']:
        # Exudyn also calls the post-step function once at t = 0 (initial state, stretch 0);
        # the mean is taken over the step-end samples t = h, 2h, ..., 20 s only
        tr = np.array(rec['t'])
        sel = tr > 0.5 * H
        for k in ('chord', 'arc', 'tip'):
            res['mean_stretch_' + k] = float(np.mean((np.array(rec[k])[sel] - L_ROPE) / L_ROPE))
        res['mean_stretch'] = res['mean_stretch_chord']
        res['stretch_samples'] = int(sel.sum())
    ref = REFERENCE.get(n_el)
    if ref:
        res['ref_period_s'], res['ref_mean_stretch'] = ref
        res['period_rel_err'] = (period - ref[0]) / ref[0]
        if 'mean_stretch' in res:
            res['stretch_rel_err'] = (res['mean_stretch'] - ref[1]) / ref[1]
    return res


def _module_name():
    mods = [m for m in sys.modules if m.startswith('exudyn.exudynCPP') and m.count('.') == 1]
    return mods[0].split('.')[1] if mods else 'unknown'


def fmt(x, f):
    return 'n/a' if x is None or (isinstance(x, float) and math.isnan(x)) else format(x, f)


HEADER = ('| N | model | solve CPU s | wall s | real-time factor | period s (rel. err) '
          '| mean stretch (rel. err) | Newton it./step (Jac./step) | completed 20 s |\n'
          '|---|---|---|---|---|---|---|---|---|')


def row(r):
    model = '3D ANCF, ' + ('sphere+joint' if r['payload'] == 'sphere' else 'point')
    per = f"{fmt(r['period_s'], '.4f')} ({fmt(r.get('period_rel_err'), '+.2e')})"
    st = f"{fmt(r.get('mean_stretch'), '.4e')} ({fmt(r.get('stretch_rel_err'), '+.2e')})"
    nit = f"{fmt(r['newton_per_step'], '.2f')} ({fmt(r['jacobians_per_step'], '.3f')})"
    return (f"| {r['N']} | {model} | {r['cpu_s']:.3f} | {r['wall_s']:.3f} | {r['rtf']:.1f} | "
            f"{per} | {st} | {nit} | {'yes' if r['completed'] else 'no (t=%.3f)' % r['t_reached']} |")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument('--n', type=int, nargs='+', default=[10, 100, 1000])
    ap.add_argument('--repeat', type=int, default=1, help='runs per N; the minimum CPU time is reported')
    ap.add_argument('--json', type=str, default=None)
    ap.add_argument('--payload', choices=['sphere', 'point'], default='sphere')
    ap.add_argument('--spectral-radius', type=float, default=0.9,
                    help='generalized-alpha spectral radius rho_inf (Exudyn default 0.9)')
    ap.add_argument('--linear-solver', choices=['sparse', 'dense'], default='sparse')
    ap.add_argument('--fast', action='store_true',
                    help='load the exudynCPPfast module (sys.exudynFast=True; no range checks)')
    ap.add_argument('--no-rope-record', action='store_true',
                    help='do not compute the rope length per step (timing of the bare solve)')
    args = ap.parse_args()

    print(f"exudyn {exu.__version__}, python {platform.python_version()}, "
          f"rho_inf={args.spectral_radius}, linear solver={args.linear_solver}, "
          f"payload={args.payload}, module={_module_name()}", flush=True)
    print(HEADER, flush=True)
    results = []
    for n in args.n:
        runs = [run_once(n, args, record_rope=not args.no_rope_record) for _ in range(args.repeat)]
        best = min(runs, key=lambda r: r['cpu_s'])
        best = dict(best)
        best['repeat'] = args.repeat
        best['all_cpu_s'] = [r['cpu_s'] for r in runs]
        best['all_wall_s'] = [r['wall_s'] for r in runs]
        results.append(best)
        print(row(best), flush=True)
    for r in results:
        extra = ', '.join(f"{k}={fmt(r.get(k), '.4e')}" for k in
                          ('mean_stretch_chord', 'mean_stretch_arc', 'mean_stretch_tip'))
        print(f"N={r['N']}: nODE2={r['nODE2']}, nAE={r['nAE']}, steps={r['steps']}, "
              f"Newton={r['newton_iterations']}, Jacobians={r['jacobians']}, "
              f"zero crossings={r['zero_crossings']}, {extra}, "
              f"CPU all runs={['%.3f' % c for c in r['all_cpu_s']]}, error={r['error']}")
    if args.json:
        meta = {'exudyn_version': exu.__version__, 'python': platform.python_version(),
                'argv': sys.argv[1:], 'module': _module_name(), 'h': H, 't_end': T_END, 'steps': N_STEPS}
        try:
            with open('/proc/cpuinfo') as f:
                meta['cpu'] = next(l.split(':', 1)[1].strip() for l in f if l.startswith('model name'))
        except Exception:
            pass
        with open(args.json, 'w') as f:
            json.dump({'meta': meta, 'results': results}, f, indent=1)


if __name__ == '__main__':
    main()
