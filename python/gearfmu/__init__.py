"""gearfmu: speed and load sweeps of the gear-pair FMU on Dask distributed (see README, "Sweeps")."""
