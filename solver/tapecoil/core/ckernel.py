"""C kernels compiled on first use and called through cffi, as FFCx's forms are.

Some numerics are loops over many small independent pieces (a contact pair's 30 x 30 block, a
closest point on a cell) that numpy can only vectorise by materialising large temporaries. Such
a loop is written once in C, compiled into a shared library the first time it is needed and
kept in a cache directory under a name derived from its source, its declarations and the
compiler's command, and loaded in cffi's ABI mode (no Python extension is built). Every process
compiles into a file of its own and moves it into place atomically, so ranks and concurrent runs
never see half a library. A C compiler is always present where DOLFINx runs: its forms are
compiled the same way.

The cache is ``$TAPECOIL_CACHE_DIR``, else ``$XDG_CACHE_HOME/tapecoil``, else
``~/.cache/tapecoil``. The compiler is ``$CC`` (default ``cc``).
"""

from __future__ import annotations

import hashlib
import os
import shlex
import subprocess
import sys
import tempfile
from pathlib import Path

import cffi

__all__ = ["CKernel", "cache_directory"]

# no -ffast-math (finite-math-only would hide a NaN from the checks that stop a run on it); the
# contact's kernels are short loops over a pair's points, which reassociated sums would not
# speed up (the forms' long kernels do: tapecoil.core.jit)
FLAGS = ("-O2", "-fPIC", "-shared", "-std=c99", "-fno-math-errno")


def cache_directory() -> Path:
    """Where compiled kernels are kept (see the module)."""
    explicit = os.environ.get("TAPECOIL_CACHE_DIR")
    if explicit:
        return Path(explicit)
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "tapecoil"


class CKernel:
    """A C source compiled into a shared library on first use (see the module).

    ``source``: the C code; ``declarations``: the cffi declarations of the functions it exports
    (C prototypes); ``name``: a readable stem for the library's file. :attr:`lib` holds the
    functions and :attr:`ffi` the cffi instance (``ffi.from_buffer`` passes numpy arrays).
    """

    def __init__(self, source: str, declarations: str, name: str):
        self.ffi = cffi.FFI()
        self.ffi.cdef(declarations)
        compiler = shlex.split(os.environ.get("CC", "cc"))
        digest = hashlib.sha256(
            "\0".join([source, declarations, " ".join(compiler), " ".join(FLAGS), sys.platform]).encode()
        ).hexdigest()[:16]
        directory = cache_directory()
        path = directory / f"{name}-{digest}.so"
        if not path.exists():
            self._compile(source, compiler, directory, path)
        self.path = path
        self.lib = self.ffi.dlopen(str(path))

    @staticmethod
    def _compile(source: str, compiler: list[str], directory: Path, path: Path) -> None:
        try:
            directory.mkdir(parents=True, exist_ok=True)
        except OSError as error:
            raise RuntimeError(
                f"cannot create the kernel cache directory {directory} ({error}); set TAPECOIL_CACHE_DIR "
                "to a writable directory"
            ) from error
        with tempfile.TemporaryDirectory(dir=directory) as work:
            c_file = Path(work) / "kernel.c"
            c_file.write_text(source)
            target = Path(work) / path.name
            command = [*compiler, *FLAGS, str(c_file), "-o", str(target), "-lm"]
            try:
                done = subprocess.run(command, capture_output=True, text=True, check=False)
            except FileNotFoundError as error:
                raise RuntimeError(
                    f"no C compiler '{compiler[0]}' to build the kernel {path.name} (set CC)"
                ) from error
            if done.returncode != 0:
                raise RuntimeError(f"compiling {path.name} failed:\n{' '.join(command)}\n{done.stderr}")
            os.replace(target, path)  # atomic: another process sees the old name or the whole file

    def pointer(self, array, ctype: str = "double *"):
        """A C pointer to the data of a C-contiguous numpy ``array`` (kept alive by the caller)."""
        if not array.flags["C_CONTIGUOUS"]:
            raise ValueError("a kernel's array must be C-contiguous")
        return self.ffi.cast(ctype, self.ffi.from_buffer(array))
