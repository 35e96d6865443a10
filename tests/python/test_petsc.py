"""The petsc and slepc backends through the Python bindings (a build with -DCORRLAP_WITH_PETSC=ON;
ctest python_petsc): the same registry as the CLI, so solve(..., solver="petsc") and
eigs(..., eigen_solver="slepc") give CHOLMOD's solutions and Spectra's eigenvalues. The interpreter
is one MPI process (an MPI singleton); docs/python.md says what that means under mpirun.
"""
import numpy as np
import pytest
import scipy.sparse as sp

import corrlap

H = 0.2


@pytest.fixture(scope="module")
def operators():
    V, F = corrlap.digitize("sphere1", h=H)
    N = corrlap.true_normals("sphere1", V, F)
    L, M = corrlap.laplacian(V, F, method="fem", face_normals=N)
    return L, M


def test_backends_lists_petsc_and_slepc():
    linear, eigen = corrlap.backends()
    assert "petsc" in linear
    assert "slepc" in eigen


def test_petsc_mumps_and_gamg_equal_cholmod(operators):
    L, M = operators
    A = sp.csc_matrix(M - 0.1 * L)
    b = np.random.default_rng(3).standard_normal((A.shape[0], 2))
    x0 = corrlap.solve(A, b, solver="cholmod")
    x = corrlap.solve(A, b, solver="petsc")
    assert np.abs(x - x0).max() < 1e-10 * np.abs(x0).max()
    x = corrlap.solve(A, b, solver="petsc", ksp_type="cg", pc_type="gamg", rtol=1e-10)
    assert np.abs(x - x0).max() < 1e-7 * np.abs(x0).max()


def test_slepc_equals_shift_invert(operators):
    L, M = operators
    v0, _ = corrlap.eigs(L, M, k=9, positive=True)
    v, U = corrlap.eigs(L, M, k=9, eigen_solver="slepc", positive=True)
    assert np.abs(v - v0).max() < 1e-8 * v0.max()
    assert np.abs(U.T @ (M @ U) - np.eye(9)).max() < 1e-8


def test_bad_petsc_option_is_a_value_error(operators):
    L, M = operators
    with pytest.raises(ValueError, match="cholesky, gamg, hypre"):
        corrlap.solve(sp.csc_matrix(M - L), np.ones(M.shape[0]), solver="petsc", pc_type="ilu0")
