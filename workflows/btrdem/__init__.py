"""btr-dem workflows: compare BTR packings with their DEM relaxation, a DEM pour reference,
error against run time, and a stability sweep. Debian's /usr/bin/python3 only (numpy, scipy,
matplotlib with the Agg backend)."""

__version__ = "0.1.0"
