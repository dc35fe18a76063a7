// Reading a dropped or picked file with progress, and saving text as a download.

/** Reads `file`, reporting the fraction read (a big STL takes a moment). */
export function readWithProgress(file: File, onProgress: (fraction: number) => void): Promise<ArrayBuffer> {
  return new Promise((resolve, reject) => {
    const reader = new FileReader();
    reader.onprogress = (event) => {
      if (event.lengthComputable && event.total > 0) onProgress(event.loaded / event.total);
    };
    reader.onload = () => resolve(reader.result as ArrayBuffer);
    reader.onerror = () => reject(new Error(`cannot read ${file.name}: ${reader.error?.message ?? "unknown error"}`));
    reader.readAsArrayBuffer(file);
  });
}

/** Offers `text` as a file download named `name` (no server involved). */
export function saveText(text: string, name: string): void {
  const url = URL.createObjectURL(new Blob([text], { type: "text/plain" }));
  const link = document.createElement("a");
  link.href = url;
  link.download = name;
  document.body.append(link);
  link.click();
  link.remove();
  setTimeout(() => URL.revokeObjectURL(url), 10_000);
}
