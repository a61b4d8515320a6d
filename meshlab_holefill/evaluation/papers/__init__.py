"""The papers' own experiments, rerun on our filters: Xie and Zou's sphere (:mod:`.hpde_sphere`)."""

__all__ = ["hpde_sphere"]
