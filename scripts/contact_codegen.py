#!/usr/bin/python3
"""Compares the machine code of the contact force passes of two builds, pass by pass.

Usage: /usr/bin/python3 scripts/contact_codegen.py [--all] [--build DIR] OLD_REV [NEW_REV]

Compiles md/compute/ContactForce.cpp of two git revisions (NEW_REV: default the work tree) with
the compile command CMake recorded for it (DIR/compile_commands.json, default build/), then
compares every instantiation of ContactForceFunctor's passes (objdump -d). Each pass is reported
as identical (the same instructions), "same up to registers" (the same after renaming registers,
stack slots and field offsets and dropping code addresses) or as the count
of lines that still differ. By default only the passes of the two benchmark workloads are listed
(docs/ARCHITECTURE.md, "The contact pass"); --all lists every instantiation that differs.

The cheap first check for a change of the contact pass: a pass that compiles to the same
instructions needs no timing; one that does not is timed (the paper-scale neutral run and
scripts/bench_charged.sh, interleaved, at least 5 pairs). Exit status 0 also when passes differ;
2 on bad input.
"""
import argparse
import difflib
import json
import pathlib
import re
import shlex
import subprocess
import sys
import tempfile

SOURCE = "md/compute/ContactForce.cpp"
# The passes the benchmarks run: the paper-scale neutral run (the compressed pair form with
# charging and the fused step) and the charged bench (the row pass with the fast Coulomb force,
# with and without the fused step).
BENCHMARKED = {
    "PairsPass<HertzViscoelastic, false, false, true, true>": "neutral: pair pass",
    "GatherPass<HertzViscoelastic, false, false, true, true>": "neutral: gather pass",
    "BlockedLoop<HertzViscoelastic, true, true, true, true>": "charged: row pass, fused step",
    "BlockedLoop<HertzViscoelastic, true, true, true, false>": "charged: row pass",
}


def fail(message):
    print(f"contact_codegen.py: {message}", file=sys.stderr)
    sys.exit(2)


def compile_command(build):
    path = build / "compile_commands.json"
    if not path.is_file():
        fail(f"--build: no {path} (configure the build first: bash scripts/setup.sh)")
    for entry in json.loads(path.read_text()):
        if entry["file"].endswith(SOURCE):
            return entry["directory"], shlex.split(entry["command"])
    fail(f"{path} has no entry for {SOURCE}")


def compile_at(rev, root, build, out, tmp):
    """Compiles SOURCE of revision rev (None: the work tree) to the object file out."""
    directory, cmd = compile_command(build)
    tree = root
    if rev is not None:
        tree = pathlib.Path(tmp) / rev.replace("/", "_")
        tree.mkdir()
        archive = subprocess.run(["git", "-C", str(root), "archive", rev], capture_output=True)
        if archive.returncode != 0:
            fail(f"'{rev}' is not a revision of {root}")
        subprocess.run(["tar", "-x", "-C", str(tree)], input=archive.stdout, check=True)
    args = []
    skip = False
    for a in cmd:
        if skip:
            skip = False
            continue
        if a == "-o":
            args += ["-o", str(out)]
            skip = True
        elif a == "-c":
            continue
        elif a.endswith(SOURCE):
            continue
        else:
            args.append(a.replace(f"-I{root}", f"-I{tree}"))
    args += ["-c", str(tree / SOURCE)]
    subprocess.run(args, cwd=directory, check=True)


def passes(obj):
    """Each ContactForceFunctor pass of obj: name -> (raw lines, renamed lines)."""
    text = subprocess.run(["objdump", "-d", "-C", "--no-show-raw-insn", str(obj)],
                          capture_output=True, text=True, check=True).stdout
    found, name = {}, None
    for line in text.splitlines():
        head = re.match(r"^[0-9a-f]+ <(.*)>:$", line)
        if head:
            name = head.group(1) if "ContactForceFunctor" in head.group(1) else None
            if name:
                found[name] = []
            continue
        if line.startswith("Disassembly of section"):
            name = None
        elif name and line.strip():
            found[name].append(re.sub(r"^\s*[0-9a-f]+:\s*", "", line))
    return {short(k): (v, [renamed(x) for x in v]) for k, v in found.items()}


def short(name):
    """PairsPass<Model, EXT, FAST_COULOMB, CHARGING, ADVANCE> and the like for the loop bodies."""
    name = re.sub(r"granagg::md::|\(anonymous namespace\)::", "", name)
    body = re.match(r"BlockRangeLoop<(\w+)<ContactForceFunctor<([^>]*)> > >::operator\(\)", name)
    if body:
        return f"{body.group(1)}<{body.group(2)}>"
    body = re.match(r"BlockedLoop<ContactForceFunctor<([^>]*)>, CombineStepAccum>::operator", name)
    if body:
        return f"BlockedLoop<{body.group(1)}>"
    return name


def renamed(line):
    line = re.sub(r"#.*", "", line)
    line = re.sub(r"[0-9a-f]+ <.*>$", "L", line.strip())  # jump and call targets
    line = re.sub(r"%[a-z0-9]+", "R", line)  # registers
    line = re.sub(r"-?0x[0-9a-f]+\(R\)", "S(R)", line)  # stack slots and field offsets
    return re.sub(r"nop.*", "nop", line).strip()


def differing(a, b):
    """Lines of a and b outside their longest matching blocks."""
    same = sum(m.size for m in difflib.SequenceMatcher(None, a, b, autojunk=False)
               .get_matching_blocks())
    return len(a) + len(b) - 2 * same


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("old_rev")
    ap.add_argument("new_rev", nargs="?")
    ap.add_argument("--build", default="build")
    ap.add_argument("--all", action="store_true")
    opt = ap.parse_args()
    root = pathlib.Path(subprocess.run(["git", "rev-parse", "--show-toplevel"],
                                       capture_output=True, text=True).stdout.strip())
    build = (root / opt.build) if not pathlib.Path(opt.build).is_absolute() else \
        pathlib.Path(opt.build)
    with tempfile.TemporaryDirectory() as tmp:
        old_o, new_o = pathlib.Path(tmp) / "old.o", pathlib.Path(tmp) / "new.o"
        compile_at(opt.old_rev, root, build, old_o, tmp)
        compile_at(opt.new_rev, root, build, new_o, tmp)
        old, new = passes(old_o), passes(new_o)
    print(f"# contact passes: {opt.old_rev} -> {opt.new_rev or 'work tree'} "
          f"({len(old)} functions)")
    print(f"{'instructions':>13}  {'verdict':<28} pass")
    differ = 0
    for name in sorted(set(old) | set(new)):
        if name not in old or name not in new:
            print(f"{'':>13}  {'only in ' + ('new' if name in new else 'old'):<28} {name}")
            differ += 1
            continue
        (a_raw, a_ren), (b_raw, b_ren) = old[name], new[name]
        if a_raw == b_raw:
            verdict = "identical"
        elif a_ren == b_ren:
            verdict = "same up to registers"
        else:
            verdict = f"{differing(a_ren, b_ren)} lines differ"
            differ += 1
        if name in BENCHMARKED or (opt.all and verdict != "identical"):
            label = BENCHMARKED.get(name, "")
            print(f"{len(a_raw):>6}{len(b_raw):>7}  {verdict:<28} {name}"
                  + (f"  ({label})" if label else ""))
    print(f"# {differ} of {len(old)} functions differ beyond register allocation")


if __name__ == "__main__":
    main()
