"""Benchmarks: speed against error of each stage, written to ``reports/`` (never run as tests).

``fe`` (``softhand bench fe``), ``calibration`` (``softhand bench calibration``) and
``handshake`` (``softhand bench handshake``); ``common`` holds what every report states about the
machine. This package sits above the stages: it may import any of them, none imports it.
"""
