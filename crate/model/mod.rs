//! DMBN and DMBN-PTE (burn).
