#!/usr/bin/env python3
"""The Yocto recipe against the build and the Debian packaging.

Every find_package / find_dependency / pkg_check_modules in the repository's
CMake files, and every header-only library the sources include without one,
must map to a recipe the recipe depends on (DEPENDS, or the PACKAGECONFIG that
turns that part of the build on). The recipe's packages must be the ones
packaging/debian/control lists, and the versions must agree.

Usage: check_recipe.py [ROOT] [--recipe BB] [--control CONTROL]
"""
import argparse
import os
import re
import sys

# CMake package (or "Package:COMPONENT") or pkg-config module -> recipes.
RECIPES = {
    "glm": ["glm"],
    "draco": ["draco"],
    "GeographicLib": ["geographiclib"],
    "CGAL": ["cgal", "gmp", "mpfr", "boost"],  # header-only: its dependencies are ours
    "meshoptimizer": ["meshoptimizer"],
    "zstd": ["zstd"],
    "nlohmann_json": ["nlohmann-json"],
    "CLI11": ["cli11"],
    "ZLIB": ["zlib"],
    "BZip2": ["bzip2"],
    "EXPAT": ["expat"],
    "OpenSSL": ["openssl"],
    "CURL": ["curl"],
    "OpenGL:EGL": ["virtual/egl"],
    "pkg:osmesa": ["mesa"],
    "pkg:stb": ["stb"],
    "pkg:libwebp": ["libwebp"],
    "pkg:libzip": ["libzip"],
    "pkg:glesv2": ["virtual/libgles2"],
}

# Names that need no recipe, and why.
EXCLUDED = {
    "blvd": "the SDK itself (samples built against an installed SDK)",
    "GTest": "tests only (BLVD_BUILD_TESTS, off in packages)",
    "benchmark": "tests only (tests/bench, QUIET)",
    "Python3": "the tests' interpreter, a build-host tool",
    "PkgConfig": "pkg-config itself: inherit pkgconfig",
    "Threads": "the C library",
    "X11": "samples/vcan_drive's optional window (QUIET)",
}

# Header-only libraries found by #include alone: prefix -> (recipes, where).
INCLUDES = {
    "osmium/": (["libosmium", "protozero"], "sdk/bake (libosmium reads PBF with protozero)"),
    "GLES3/": (["virtual/libgles2"], "sdk/render/gl_api.h"),
}
INCLUDE_DIRS = ["sdk", "adapters", "include"]

# Files under these prefixes may be met by that PACKAGECONFIG's dependencies.
OPTIONAL = {"samples/": "samples", "sdk/bake/": "tools"}
# A find_package inside if(OPTION) ... endif() may be met by that PACKAGECONFIG's.
OPTION_PACKAGECONFIG = {"BLVD_BUILD_TOOLS": "tools", "BLVD_WITH_OSMESA": "osmesa", "BLVD_BUILD_SAMPLES": "samples"}

SKIP_DIRS = {".git", "out"}  # and build*/
PKG_KEYWORDS = {"REQUIRED", "QUIET", "IMPORTED_TARGET", "GLOBAL", "NO_CMAKE_PATH",
                "NO_CMAKE_ENVIRONMENT_PATH"}


def cmake_files(root):
    for top, dirs, files in os.walk(root):
        rel = os.path.relpath(top, root)
        if rel == ".":
            dirs[:] = [d for d in dirs if d not in SKIP_DIRS and not d.startswith("build")]
        dirs[:] = [d for d in dirs if d != ".git"]
        for f in files:
            if f == "CMakeLists.txt" or f.endswith(".cmake") or f.endswith(".cmake.in"):
                yield os.path.join(top, f)


def strip_cmake_comments(text):
    text = re.sub(r"#\[(=*)\[.*?\]\1\]", "", text, flags=re.S)
    out = []
    for line in text.splitlines():
        quoted = False
        for i, c in enumerate(line):
            if c == '"' and (i == 0 or line[i - 1] != "\\"):
                quoted = not quoted
            elif c == "#" and not quoted:
                line = line[:i]
                break
        out.append(line)
    return "\n".join(out)


def option_at(text, pos):
    """The PACKAGECONFIG of the innermost if(OPTION) block around text[pos], or None."""
    stack = []
    for m in re.finditer(r"\b(if|else|elseif|endif)\s*\(([^)]*)\)", text[:pos], re.I):
        word, cond = m.group(1).lower(), m.group(2).strip()
        if word == "if":
            stack.append(OPTION_PACKAGECONFIG.get(cond))
        elif word == "endif" and stack:
            stack.pop()
        elif stack:  # else / elseif: not the option's branch
            stack[-1] = None
    return next((pc for pc in reversed(stack) if pc), None)


def cmake_needs(root):
    """[(key, file, PACKAGECONFIG or None)] for every package a CMake file asks for."""
    needs = []
    call = re.compile(r"\b(find_package|find_dependency|pkg_check_modules|pkg_search_module)\s*\(([^)]*)\)", re.I)
    for path in cmake_files(root):
        rel = os.path.relpath(path, root)
        with open(path, encoding="utf-8") as f:
            text = strip_cmake_comments(f.read())
        for m in call.finditer(text):
            cmd, args = m.group(1).lower(), m.group(2).split()
            if not args:
                continue
            if cmd in ("find_package", "find_dependency"):
                name = args[0]
                if name in EXCLUDED:
                    continue
                comps = []
                if "COMPONENTS" in args:
                    comps = [a for a in args[args.index("COMPONENTS") + 1:] if a.isidentifier()]
                for key in ([f"{name}:{c}" for c in comps] or [name]):
                    needs.append((key, rel, option_at(text, m.start())))
            else:
                for mod in args[1:]:
                    if mod.upper() in PKG_KEYWORDS:
                        continue
                    mod = re.split(r"[<>=]", mod)[0]
                    if mod and mod not in EXCLUDED:
                        needs.append(("pkg:" + mod, rel, option_at(text, m.start())))
    return needs


def include_needs(root):
    needs = []
    inc = re.compile(r"^\s*#\s*include\s*<([^>]+)>", re.M)
    for d in INCLUDE_DIRS:
        for top, _, files in os.walk(os.path.join(root, d)):
            for f in files:
                if not f.endswith((".h", ".hpp", ".c", ".cpp")):
                    continue
                path = os.path.join(top, f)
                with open(path, encoding="utf-8", errors="replace") as fh:
                    headers = inc.findall(fh.read())
                for prefix in INCLUDES:
                    if any(h.startswith(prefix) for h in headers):
                        needs.append(("include:" + prefix, os.path.relpath(path, root), None))
    return needs


def bb_assignments(path):
    """[(name, op, value)] of a .bb file, continuation lines joined."""
    with open(path, encoding="utf-8") as f:
        text = f.read().replace("\\\n", " ")
    assign = re.compile(r'^([A-Za-z0-9_${}/:\[\].+-]+?)\s*(\?\?=|\?=|\+=|=\+|\.=|=\.|:=|=)\s*"(.*)"\s*$')
    out = []
    for line in text.splitlines():
        m = assign.match(line.strip())
        if m and not line.lstrip().startswith("#"):
            out.append(m.groups())
    return out


def parse_recipe(path):
    depends, pkgconfig, default_pc, packages, files = [], {}, [], [], set()
    for name, op, value in bb_assignments(path):
        if name in ("DEPENDS", "DEPENDS:append", "DEPENDS:prepend"):
            if op in ("=", ":=", "?=", "??="):
                depends = value.split()
            else:
                depends += value.split()
        elif name.startswith("PACKAGECONFIG["):
            fields = value.split(",")
            pkgconfig[name[len("PACKAGECONFIG["):-1]] = fields[2].split() if len(fields) > 2 else []
        elif name == "PACKAGECONFIG":
            default_pc = value.split()
        elif name == "PACKAGES":
            packages += [p for p in value.split() if "$" not in p]
        elif name.startswith("FILES:"):
            files.add(name[len("FILES:"):])
    return depends, pkgconfig, default_pc, packages, files


def debian_packages(control):
    with open(control, encoding="utf-8") as f:
        return re.findall(r"^Package:\s*(\S+)", f.read(), re.M)


def versions(root, recipe, debian_dir):
    with open(os.path.join(root, "CMakeLists.txt"), encoding="utf-8") as f:
        cmake = re.search(r"project\(\s*blvd\s+VERSION\s+([0-9.]+)", f.read()).group(1)
    with open(os.path.join(debian_dir, "changelog"), encoding="utf-8") as f:
        deb = re.match(r"\S+ \(([^)]+)\)", f.readline()).group(1)
    with open(os.path.join(debian_dir, "source", "format"), encoding="utf-8") as f:
        fmt = f.read().strip()
    bb = re.match(r"[^_]+_(.+)\.bb$", os.path.basename(recipe)).group(1)
    return cmake, deb, fmt, bb


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    ap = argparse.ArgumentParser()
    ap.add_argument("root", nargs="?", default=os.path.normpath(os.path.join(here, "..", "..")))
    ap.add_argument("--recipe")
    ap.add_argument("--control")
    a = ap.parse_args()
    root = a.root
    recipe = a.recipe or os.path.join(root, "packaging/yocto/meta-blvd/recipes-graphics/blvd/blvd_0.1.0.bb")
    control = a.control or os.path.join(root, "packaging/debian/control")
    fails = []

    depends, pkgconfig, default_pc, packages, files = parse_recipe(recipe)
    # What the build always asks for must be in DEPENDS, not in a PACKAGECONFIG
    # (even a default one): a recipe with that PACKAGECONFIG off must still build.
    always = set(depends)
    fails += [f"PACKAGECONFIG ??= names {n}, which has no PACKAGECONFIG[{n}]" for n in default_pc if n not in pkgconfig]

    needs = cmake_needs(root) + include_needs(root)
    required = set()
    for key, where, option_pc in needs:
        if key.startswith("include:"):
            recipes = INCLUDES[key[len("include:"):]][0]
        elif key in RECIPES:
            recipes = RECIPES[key]
        else:
            fails.append(f"{key} ({where}) has no recipe in check_recipe.py's RECIPES: map it or exclude it with a reason")
            continue
        have = set(always)
        if option_pc:
            have |= set(pkgconfig.get(option_pc, []))
        for prefix, pc in OPTIONAL.items():
            if where.startswith(prefix):
                have |= set(pkgconfig.get(pc, []))
        for r in recipes:
            required.add(r)
            if r not in have:
                fails.append(f"{os.path.basename(recipe)} does not depend on {r} ({key}, {where})")
    extra = sorted(set(depends) - required)

    deb = debian_packages(control)
    if sorted(packages) != sorted(deb):
        fails.append(f"recipe packages {sorted(packages)} != debian/control packages {sorted(deb)}")
    for p in packages:
        if p not in files:
            fails.append(f"recipe package {p} has no FILES:{p}")

    cmake_v, deb_v, fmt, bb_v = versions(root, recipe, os.path.dirname(control))
    if fmt == "3.0 (native)" and "-" in deb_v:
        fails.append(f"debian/changelog version {deb_v} has a revision, which 3.0 (native) refuses")
    if len({cmake_v, deb_v.split("-")[0], bb_v}) != 1:
        fails.append(f"versions differ: CMakeLists.txt {cmake_v}, debian/changelog {deb_v}, recipe {bb_v}")

    keys = sorted({k for k, _, _ in needs})
    print(f"check_recipe: {len(keys)} CMake/pkg-config/include names -> {len(required)} recipes; "
          f"recipe DEPENDS {len(depends)}; packages {' '.join(sorted(packages))}; version {cmake_v}")
    if extra:
        print(f"check_recipe: note: DEPENDS that nothing scanned asks for: {' '.join(extra)}")
    for f in fails:
        print("FAIL: " + f)
    print(f"check_recipe: {len(fails)} problem(s)" if fails else "check_recipe: OK")
    return 1 if fails else 0


if __name__ == "__main__":
    sys.exit(main())
