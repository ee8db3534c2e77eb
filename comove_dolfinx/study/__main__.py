"""``python -m comove_dolfinx.study SCENE ...``: ``comove study`` (its options), also as the module that
``mpiexec -n N python -m mpi4py.futures -m comove_dolfinx.study ...`` runs on rank 0 (docs/study.md).
The workers of that pool import this module too (as multiprocessing does the main module), under
another name: they must not start a study."""
import sys

from ..cli import main

if __name__ == "__main__":
    sys.exit(main(["study", *sys.argv[1:]]))
