#!/usr/bin/env python3
"""cputime.py OUT.json CMD...: the CPU time of CMD and of every process it starts (Ray's GCS,
raylet, agents and workers included, even those orphaned or reaped without wait: rusage and
`time` miss them), measured by a cgroup-v1 cpuacct group made for the run and removed
afterwards (needs root and /sys/fs/cgroup/cpuacct); also wall time and exit code, as JSON
in OUT.json and on stderr. `cpu` is the group's cpuacct.usage (user + sys, nanosecond
accounting); `user` and `sys` are its tick counts (cpuacct.stat). benches/ray_cpu.sh uses it."""
import json, os, sys, time

root = "/sys/fs/cgroup/cpuacct"
cg = f"{root}/pyfix-bench-{os.getpid()}"
os.mkdir(cg)
out, cmd = sys.argv[1], sys.argv[2:]
try:
    with open(f"{cg}/cgroup.procs", "w") as f:
        f.write(str(os.getpid()))
    t0 = time.time()
    pid = os.fork()
    if pid == 0:
        os.execvp(cmd[0], cmd)
    _, status = os.waitpid(pid, 0)
    wall = time.time() - t0
    # Wait for what the command left running (Ray's daemons stopping) to end.
    deadline = time.time() + 60
    while time.time() < deadline:
        procs = [p for p in open(f"{cg}/cgroup.procs").read().split() if int(p) != os.getpid()]
        if not procs:
            break
        time.sleep(0.1)
    left = len(procs)
    rd = lambda n: int(open(f"{cg}/{n}").read()) / 1e9
    hz = os.sysconf("SC_CLK_TCK")
    stat = dict(l.split() for l in open(f"{cg}/cpuacct.stat"))
    res = {"user": int(stat["user"]) / hz, "sys": int(stat["system"]) / hz,
           "cpu": rd("cpuacct.usage"), "wall": wall, "rc": os.waitstatus_to_exitcode(status),
           "left_running": left}
finally:
    with open(f"{root}/cgroup.procs", "w") as f:
        f.write(str(os.getpid()))
    time.sleep(0.1)
    try:
        os.rmdir(cg)
    except OSError as e:
        print(f"cputime: {cg} not removed: {e}", file=sys.stderr)
json.dump(res, open(out, "w"))
print(json.dumps(res), file=sys.stderr)
