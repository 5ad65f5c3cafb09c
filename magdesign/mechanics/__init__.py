"""Mechanics: materials, elastomer layers and domes (SI: m, N, Pa)."""
