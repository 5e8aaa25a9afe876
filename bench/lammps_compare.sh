#!/usr/bin/env bash
# ravel against LAMMPS on the same fabric, one core each, in one run (issue 21's speed peer).
#
# LAMMPS (Debian's `lammps`, installed here if missing) runs the default scene's quarter
# fabric as a spring network: 72 x 72 crossings, two nodes per crossing (warp and weft
# yarn, L1 apart), springs of the yarns' instantaneous stiffness K1 A / L along each yarn,
# the clamped edge fixed, the symmetry planes held, the 12 mm sphere driven through it at
# 260 m/s as a moving repulsive region, velocity Verlet at ravel's time step. Two networks:
#   lammps_spring_network     the issue's peer: tension-only springs (no force when shorter
#                             than their rest length, a tabulated law) that break for good
#                             at the yarn's 5.2 % failure strain (fix bond/break, checked
#                             every step as ravel checks its elements)
#   lammps_harmonic_network   harmonic springs that push as well as pull and never break:
#                             the cheapest network LAMMPS runs, a floor
# No friction, crossing contact, bending, viscoelasticity or energy ledger in either: what
# an explicit network of this size costs per step, not the same physics. ravel runs the
# real default scene to the same simulated time (102 us, 1672 steps), and its pin-jointed
# model (the paper's mu = infinity: one node per crossing, no sliding contact, the physics
# class of the LAMMPS network; 5184 nodes, so its per-node-step figure counts half as many
# nodes), each on one thread and on two. All are timed as whole processes and by their own
# loop timers. Last rows: ratios per node-step against LAMMPS and the 2-thread speed-ups.
#
# usage: bench/lammps_compare.sh [BUILD_DIR]        prints CSV on stdout
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-$root/build}
ravel=$build/app/ravel
[ -x "$ravel" ] || { echo "no $ravel: build first (scripts/setup)" >&2; exit 2; }
if ! command -v lmp >/dev/null 2>&1; then
  echo "lammps_compare: installing Debian's lammps" >&2
  sudo_cmd=()
  [ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
  DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends lammps >/dev/null
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# The quarter fabric as a LAMMPS data file (SI units), generated like core/model.cpp lays it out.
python3 - "$work" <<'EOF'
import math, sys
work = sys.argv[1]
L0, L1 = 0.844e-3, 0.2e-3
n = 2 * int(0.060 / L0 // 1) + 1        # yarns per direction in the whole fabric (143)
h = n // 2                              # quarter: grid indices 0..h (72 per direction)
m = 9.4e-8                              # node mass, kg
E, A = 7.28e10, 7.64e-8                 # K1 (instantaneous modulus), yarn cross-section
atoms, bonds = [], []
def nid(fam, i, j): return 1 + fam * (h + 1) ** 2 + i * (h + 1) + j
for fam in (0, 1):                      # 0 warp (along y), 1 weft (along x)
    for i in range(h + 1):
        for j in range(h + 1):
            up = (i + j) % 2 == 0       # warp on top where I + J is even
            z = (0.5 if up == (fam == 0) else -0.5) * L1
            atoms.append((nid(fam, i, j), 1, i * L0, j * L0, z))
for i in range(h + 1):
    for j in range(h):
        bonds.append((nid(0, i, j), nid(0, i, j + 1)))   # warp yarn I, along y
        bonds.append((nid(1, j, i), nid(1, j + 1, i)))   # weft yarn J, along x
with open(work + "/fabric.data", "w") as f:
    f.write("ravel quarter fabric\n\n%d atoms\n%d bonds\n1 atom types\n1 bond types\n\n" % (len(atoms), len(bonds)))
    f.write("-0.001 0.0615 xlo xhi\n-0.001 0.0615 ylo yhi\n-0.08 0.02 zlo zhi\n\nMasses\n\n1 %.6g\n\nAtoms # bond\n\n" % m)
    for a in atoms:
        f.write("%d 1 %d %.9g %.9g %.9g\n" % (a[0], a[1], a[2], a[3], a[4]))
    f.write("\nBonds\n\n")
    for k, (a, b) in enumerate(bonds):
        f.write("%d 1 %d %d\n" % (k + 1, a, b))
Lel = math.sqrt(L0 ** 2 + L1 ** 2)
k = E * A / Lel                         # N/m; LAMMPS harmonic: E = K (r - r0)^2, K = k / 2
eps_f = 0.052                           # failure strain (the default scene's)
r_fail = Lel * (1 + eps_f)
with open(work + "/params.in", "w") as f:
    f.write("variable K equal %.9g\nvariable r0 equal %.9g\nvariable xclamp equal %.9g\n" % (k / 2, Lel, h * L0 - 1e-9))
    f.write("variable rfail equal %.12g\n" % r_fail)
# The tension-only law as a LAMMPS bond table: force k (r - r0) between r0 and r_fail, none
# below r0; r0 and r_fail fall on grid points (spacing r0 / 1000), so linear interpolation
# is exact. fix bond/break deletes a bond once it is longer than r_fail, before the next
# force evaluation, so the table need not reach further than a few points past it.
dr, n_fail = Lel / 1000, int(round(1000 * (1 + eps_f)))
with open(work + "/tension.table", "w") as f:
    f.write("# tension-only spring, k = %.6g N/m, r0 = %.6g m\n\nTENSION\nN %d\n\n" % (k, Lel, n_fail + 10))
    for i in range(1, n_fail + 11):
        r = i * dr
        taut = 1000 < i <= n_fail
        f.write("%d %.12g %.12g %.12g\n" % (i, r, 0.5 * k * (r - Lel) ** 2 if taut else 0.0, -k * (r - Lel) if taut else 0.0))
print(n_fail + 10, file=open(work + "/table_points", "w"))
print(len(atoms), file=open(work + "/nodes", "w"))
EOF
# The two networks differ only in their bond law (BOND_LAW below).
cat >"$work/in.template" <<'EOF'
units si
atom_style bond
boundary f f f
read_data fabric.data
include params.in
BOND_LAW
pair_style none
variable xc atom x>${xclamp}
group clamp variable xc
variable px atom x<1e-9
group plane_x variable px
variable py atom y<1e-9
group plane_y variable py
# The sphere: R = 6 mm, its lowest point at the fabric at t = 0, moving down at 260 m/s; a
# node inside it is pushed out with F = K (R - r)^2 (LAMMPS' spherical indenter).
variable zc equal 0.0061-260*step*dt
fix push all indent 1e12 sphere 0 0 v_zc 0.006 side out units box
fix verlet all nve
fix clamp clamp setforce 0 0 0
fix px plane_x setforce 0 NULL NULL
fix py plane_y setforce NULL 0 NULL
timestep 6.099461334530171e-08
thermo 0
thermo_style custom step f_push[3]
run 1672
EOF
points=$(cat "$work/table_points")
sed "s|BOND_LAW|bond_style table linear $points\nbond_coeff 1 tension.table TENSION\nfix break all bond/break 1 1 \${rfail}|" \
  "$work/in.template" >"$work/in.tension"
sed 's|BOND_LAW|bond_style harmonic\nbond_coeff 1 ${K} ${r0}|' "$work/in.template" >"$work/in.harmonic"
nodes=$(cat "$work/nodes")
steps=1672
now() { date +%s.%N; }
loop_time() { sed -n 's/^Loop time of \([0-9.e+-]*\) on .*/\1/p' "$1" | tail -1; }
t0=$(now)
(cd "$work" && lmp -in in.tension -log tension.log -screen none)
t1=$(now)
h0=$(now)
(cd "$work" && lmp -in in.harmonic -log harmonic.log -screen none)
h1=$(now)
lammps_loop=$(loop_time "$work/tension.log")
harmonic_loop=$(loop_time "$work/harmonic.log")
# ravel: the default scene (sliding model) and the pin-jointed model (the paper's mu = infinity:
# a network with no sliding contact, the physics class of the LAMMPS network), each on one
# thread and on two, to the same simulated time. Each run's loop time from its summary.
ravel_run() {  # ravel_run NAME THREADS [--set ...]: prints "nodes steps process_s loop_s"
  local name=$1 th=$2; shift 2
  local a b
  a=$(now)
  "$ravel" run --set solver.end_time_us=102 --threads "$th" "$@" --out "$work/$name" --quiet >/dev/null
  b=$(now)
  python3 - "$work/$name/summary.json" "$a" "$b" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
print(j["modelled_node_count"], j["step_count"], float(sys.argv[3]) - float(sys.argv[2]), j["wall_time_s"])
PY
}
sliding1=$(ravel_run sliding1 1)
pin1=$(ravel_run pin1 1 --set solver.model=pin_jointed)
sliding2=$(ravel_run sliding2 2)
pin2=$(ravel_run pin2 2 --set solver.model=pin_jointed)
python3 - "$nodes" "$steps" "$t0" "$t1" "$lammps_loop" "$h0" "$h1" "$harmonic_loop" \
  "$sliding1" "$pin1" "$sliding2" "$pin2" <<'EOF'
import sys
n, s, t0, t1, ll, h0, h1, hl = sys.argv[1:9]
runs = [a.split() for a in sys.argv[9:13]]
n, s = int(n), int(s)
lw, hw = float(t1) - float(t0), float(h1) - float(h0)
ll, hl = float(ll), float(hl)
per = lambda loop, nodes, steps: loop / (nodes * steps)
print("code,nodes,steps,process_wall_s,loop_s,ns_per_node_step")
print("lammps_spring_network,%d,%d,%.3f,%.3f,%.1f" % (n, s, lw, ll, per(ll, n, s) * 1e9))
print("lammps_harmonic_network,%d,%d,%.3f,%.3f,%.1f" % (n, s, hw, hl, per(hl, n, s) * 1e9))
names = ["ravel_default_scene", "ravel_pin_jointed", "ravel_default_scene_2_threads", "ravel_pin_jointed_2_threads"]
ns = {}
for name, r in zip(names, runs):
    rn, rs, rw, rl = int(r[0]), int(r[1]), float(r[2]), float(r[3])
    ns[name] = (rw, rl, per(rl, rn, rs))
    print("%s,%d,%d,%.3f,%.3f,%.1f" % (name, rn, rs, rw, rl, per(rl, rn, rs) * 1e9))
# Ratios against the LAMMPS tension network (issue 36: sliding <= 1.5x, pin-jointed <= 1.0x
# per node-step on one thread) and against the harmonic floor; the 2-thread speed-up of each
# model (issue 36: >= 1.7x; one pair here, paired medians in the README).
for label, name in (("ratio_ravel_over_lammps", "ravel_default_scene"),
                    ("ratio_pin_jointed_over_lammps", "ravel_pin_jointed")):
    rw, rl, rp = ns[name]
    print("%s,,,%.2f,%.2f,%.2f" % (label, rw / lw, rl / ll, rp / per(ll, n, s)))
rw, rl, rp = ns["ravel_default_scene"]
print("ratio_ravel_over_lammps_harmonic,,,%.2f,%.2f,%.2f" % (rw / hw, rl / hl, rp / per(hl, n, s)))
for label, one, two in (("speedup_2_threads_sliding", "ravel_default_scene", "ravel_default_scene_2_threads"),
                        ("speedup_2_threads_pin_jointed", "ravel_pin_jointed", "ravel_pin_jointed_2_threads")):
    print("%s,,,%.2f,%.2f,%.2f" % (label, ns[one][0] / ns[two][0], ns[one][1] / ns[two][1], ns[one][2] / ns[two][2]))
EOF
