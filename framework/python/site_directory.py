"""Prints the platform site directory of this interpreter under an install prefix, relative to it.

The one on the interpreter's own sys.path under that prefix when there is one (Debian's
lib/python3.11/dist-packages under /usr/local, the user site under ~/.local), else the platlib
path of the posix_prefix scheme, which PYTHONPATH must then name.
"""
import os
import site
import sys
import sysconfig

prefix = os.path.abspath(sys.argv[1])
candidates = site.getsitepackages() + [site.getusersitepackages()]
for candidate in candidates:
    if candidate.startswith(prefix + os.sep):
        print(os.path.relpath(candidate, prefix))
        sys.exit(0)
platlib = sysconfig.get_path("platlib", "posix_prefix", {"base": prefix, "platbase": prefix})
print(os.path.relpath(platlib, prefix))
