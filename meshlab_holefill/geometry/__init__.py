"""Shared geometric building blocks used by every hole-filling algorithm.

Plain numpy arrays in and out; nothing here touches pymeshlab.
"""
