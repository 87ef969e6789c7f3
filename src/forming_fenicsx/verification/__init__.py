"""Exact solutions and bounds the code is checked against: channel and radial flows, homogeneous
extension, the heat equation's exact cases, limit analysis.
"""
