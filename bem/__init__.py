"""Axisymmetric Stokes boundary element method for objects in a tube (issues 5 and 6).

Not implemented yet: this package is a placeholder so that the distribution installs the three
import packages of the project layout. Importing a solver from here raises ImportError.
"""
