"""The toy pendulum's nodes (only a simulator)."""
